"""Add a protocol's reference scores to shipped detectors (default detectors/lss-R1: the card's ``protocols`` entry
and ``bootstrap-<protocol>.npz``).

    python studies/validation/protocol/ship_protocol.py --protocol quick [--ref R1] [--cache DIR] [--workers 2]

On the card's own scenes (quick) R1's full test split is rendered into the cache and scored with every shipped
seed; the full protocol's scores must equal the card's (checked), and the protocol's frames are taken from the
same matched detections. On new scenes (quick-s1) R1 is rendered under the protocol and scored as it is.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--protocol", default="quick", help="the protocol to add (a name of measuring.PROTOCOLS)")
    parser.add_argument("--ref", default="R1", help="the reference of the shipped lss models (R1, nuscenes)")
    parser.add_argument("--cache", type=Path, default=None, help="renderings (default: rigopt validate's cache)")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    from rigopt.validation.detectors.measuring import protocol_named
    from rigopt.validation.detectors.shipped import add_protocol, default_cache, shipped_detector

    protocol = protocol_named(args.protocol)
    detector = add_protocol(shipped_detector("lss", args.ref), protocol, args.cache or default_cache(), "cpu",
                            args.workers, lambda message: print(message, flush=True))
    for seed, own in detector.card["protocols"][protocol.name]["seeds"].items():
        print(f"seed {seed}: {protocol.name} mAP {own['mAP']:.4f} (full {detector.card['seeds'][seed]['mAP']:.4f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
