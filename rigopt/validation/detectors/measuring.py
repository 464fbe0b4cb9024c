"""The protocols of measuring a rig's transfer with shipped models: which frames of the reference's test scenes
are rendered and scored. Plain data (no numpy, no torch): the command line's ``--protocol`` reads it.

``full`` scores every frame of the reference's test scenes (the pack's card and ``bootstrap.npz``). ``quick``
scores every fourth frame of the same scenes, a quarter of the work, its drops relative to the reference's own
scores on those frames (the card's ``protocols`` entry and ``bootstrap-quick.npz``). Both keep all the test
scenes, so the bootstrap's scene resamples draw the same scenes under each. ``quick-s1`` scores quick's frames of
as many new scenes (seed offset 1), a second test set to replicate a finding on, relative to the reference's own
scores there. The agreement of ``quick``
with ``full`` was pre-registered and measured in studies/validation/protocol/; it passed, and quick is the
default.
"""

from __future__ import annotations

from dataclasses import dataclass

from rigopt.errors import unknown_name


@dataclass(frozen=True)
class Protocol:
    """A measurement protocol.

    name : str, as ``--protocol`` takes it; frame_stride : int, every ``frame_stride``-th frame of each test
    scene from its first (1: all); scene_offset : int or None, the scene seed offset of the test scenes
    (``rigopt.validation.synthetic.scenes.SEED_OFFSET_STEP``): None for the scenes the models were scored on (the
    pack card's), another for as many new scenes, never seen in training or testing before.
    """

    name: str
    frame_stride: int
    scene_offset: int | None = None

    def seed_offset(self, test_data: dict) -> int:
        """The seed offset of the scenes scored."""
        return int(test_data["seed_offset"]) if self.scene_offset is None else self.scene_offset

    def frames(self, test_data: dict) -> int:
        """Frames of each test scene scored; ``test_data`` a pack card's (``scenes``, ``frames``)."""
        return len(range(0, int(test_data["frames"]), self.frame_stride))

    def samples(self, test_data: dict) -> int:
        """Samples scored in all."""
        return int(test_data["scenes"]) * self.frames(test_data)

    def describe(self, test_data: dict) -> str:
        """What the protocol scores, for every output that uses it."""
        frames = ("every frame" if self.frame_stride == 1 else
                  f"every {self.frame_stride}th frame ({self.frames(test_data)} of {test_data['frames']})")
        scenes = (f"the {test_data['scenes']} test scenes" if self.scene_offset is None else
                  f"{test_data['scenes']} new test scenes (seed offset {self.scene_offset})")
        return f"protocol {self.name}: {frames} of {scenes}, {self.samples(test_data)} samples"


FULL = Protocol("full", 1)
QUICK = Protocol("quick", 4)
#: quick's frames of as many new test scenes: a second set of scenes to replicate a finding on.
QUICK_NEW_SCENES = Protocol("quick-s1", 4, scene_offset=1)
#: The protocols by name.
PROTOCOLS: dict[str, Protocol] = {p.name: p for p in (FULL, QUICK, QUICK_NEW_SCENES)}
#: What ``rigopt validate``, ``rigopt design --measure`` and :func:`rigopt.validation.detectors.shipped.measure` use
#: unless told: quick, since its pre-registered agreement with full passed (studies/validation/protocol: on 63 rigs
#: mean |quick - full| 0.0047, Spearman rho 0.9986, largest difference 0.030).
DEFAULT_PROTOCOL = QUICK


def protocol_named(name: str) -> Protocol:
    """The protocol ``name`` (case-insensitive); a RigoptError listing the names otherwise."""
    if str(name).lower() not in PROTOCOLS:
        raise unknown_name("measurement protocol", name, tuple(PROTOCOLS))
    return PROTOCOLS[str(name).lower()]
