"""The coverage HTML report written by ``rigopt coverage RIG --compare OTHER --out DIR``: every camera of the
rig has its row, and every figure the page shows is a PNG written beside it (the page embeds the very
bytes of bev.png, rings.png and blind.png). On the box car (a user vehicle under a tmp RIGOPT_HOME) with a
two-camera rig, compared with its front camera alone.
"""

from __future__ import annotations

import base64
import json
from html.parser import HTMLParser

import pytest
from typer.testing import CliRunner

from rigopt.cli.app import app
from rigopt.rig.model import Rig
from rigopt.rig.pccr_format import write_rig

from box_car import front_and_left_rig, install_user_vehicle

PNG = b"\x89PNG\r\n\x1a\n"
FIGURES = ("bev.png", "rings.png", "blind.png")


class PageParts(HTMLParser):
    """The text of every table cell (by table, in order) and the src of every image of a page."""

    def __init__(self):
        super().__init__()
        self.tables: list[list[list[str]]] = []
        self.images: list[str] = []
        self.headings: list[str] = []
        self._cell: list[str] | None = None
        self._heading: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append([])
        elif tag == "tr":
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self._cell = []
        elif tag == "img":
            self.images.append(dict(attrs)["src"])
        elif tag in ("h1", "h2"):
            self._heading = []

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self.tables[-1][-1].append("".join(self._cell).strip())
            self._cell = None
        elif tag in ("h1", "h2"):
            self.headings.append("".join(self._heading).strip())
            self._heading = None

    def handle_data(self, data):
        for part in (self._cell, self._heading):
            if part is not None:
                part.append(data)


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """(the rig, the parsed page, the output folder)."""
    root = tmp_path_factory.mktemp("coverage_html")
    install_user_vehicle(root / "home", "htmlcar")
    rig = front_and_left_rig("vehicle.test.htmlcar", "boxrig")
    front_only = Rig("frontonly", rig.vehicle, rig.cameras[:1])
    rig_file, other_file = write_rig(rig, root / "boxrig.json"), write_rig(front_only, root / "frontonly.json")
    out = root / "out"
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("RIGOPT_HOME", str(root / "home"))
        result = CliRunner().invoke(app, ["coverage", str(rig_file), "--compare", str(other_file), "--out", str(out)])
    assert result.exit_code == 0, (result.output, result.exception)
    parts = PageParts()
    parts.feed((out / "report.html").read_text(encoding="utf-8"))
    return rig, parts, out


def test_the_folder_holds_the_page_the_json_and_the_figures(report):
    _, _, out = report
    assert sorted(p.name for p in out.iterdir()) == sorted(["coverage.json", "report.html", *FIGURES])


def test_every_camera_has_its_row_with_its_lens(report):
    rig, parts, _ = report
    cameras = next(t for t in parts.tables if t[0][:3] == ["camera", "position x, y, z (m, from the vehicle centre)",
                                                           "hfov"])
    rows = {row[0]: row for row in cameras[1:]}
    assert sorted(rows) == sorted(c.id for c in rig.cameras)
    for camera in rig.cameras:
        shown = [float(v) for v in rows[camera.id][1].split(",")]
        assert shown == pytest.approx(camera.position.tolist(), abs=0.005)
        assert rows[camera.id][2] == f"{camera.fov:.1f}°"


def test_the_cameras_of_the_json_are_those_of_the_page(report):
    rig, _, out = report
    data = json.loads((out / "coverage.json").read_text())
    assert [c["id"] for c in data["cameras"]] == [c.id for c in rig.cameras]
    assert data["compare"]["a"] == "frontonly" and data["compare"]["b"] == "boxrig"


def test_every_figure_shown_is_a_written_png(report):
    _, parts, out = report
    assert len(parts.images) == len(FIGURES)
    shown = []
    for src in parts.images:
        prefix = "data:image/png;base64,"
        assert src.startswith(prefix)  # self-contained: nothing fetched from elsewhere
        shown.append(base64.b64decode(src[len(prefix):], validate=True))
    written = [(out / name).read_bytes() for name in FIGURES]
    assert all(png.startswith(PNG) and len(png) > 10_000 for png in written)
    assert shown == written


def test_the_comparison_section_names_both_rigs(report):
    _, parts, _ = report
    assert "Comparison: boxrig minus frontonly" in parts.headings
    assert parts.headings[0] == "Coverage of rig boxrig on htmlcar"
