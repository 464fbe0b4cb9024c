"""PNG figures of a calibration study: drop and rank-error heatmaps and predicted-vs-observed scatters."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from matplotlib import colormaps
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle

from rigopt.metrics.protocol import CalibrationStudy, PairPredictions
from rigopt.rig.library import rig_names

DPI = 120
_MARKERS = {True: ("s", "control pairs"), False: ("o", "held-out pairs")}


def write_calibration_figures(study: CalibrationStudy, out_dir) -> list[Path]:
    """Write every calibration figure of ``study`` as PNG into ``out_dir`` (created); returns the paths.

    Per detector: ``drop_heatmaps_<model>.png`` and ``rank_error_<model>.png``; for all detectors:
    ``scatter.png`` (own fits) and ``joint_scatter.png`` (the joint fit).
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for model in study.models:
        stem = _file_stem(model.model)
        rigs = _rig_order(np.concatenate([model.pairs.train, model.pairs.test]))
        written.append(_save(_drop_heatmaps(model.model, model.pairs, rigs, study.control_rigs),
                             out_dir / f"drop_heatmaps_{stem}.png"))
        written.append(_save(_rank_error_heatmap(model.model, model.pairs, rigs, study.control_rigs),
                             out_dir / f"rank_error_{stem}.png"))
    written.append(_save(_model_scatters(study), out_dir / "scatter.png"))
    written.append(_save(_joint_scatter(study), out_dir / "joint_scatter.png"))
    return written


def _file_stem(name: str) -> str:
    """``name`` safe as part of a file name: runs of characters other than letters, digits, ``.-_`` become ``_``."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name.strip()) or "_"


def _rig_order(names) -> list[str]:
    """The distinct rig ``names`` with library rigs first in the benchmark order, the others after as they come."""
    library = {name.lower(): k for k, name in enumerate(rig_names())}
    distinct = list(dict.fromkeys(str(n) for n in names))
    known = sorted((n for n in distinct if n.lower() in library), key=lambda n: library[n.lower()])
    return known + [n for n in distinct if n.lower() not in library]


def _pair_matrix(pairs: PairPredictions, values, rigs: list[str]) -> np.ndarray:
    """(R, R) matrix of per-pair ``values`` with rows = training rig, columns = test rig in ``rigs`` order; NaN where
    no pair was evaluated."""
    index = {name: k for k, name in enumerate(rigs)}
    matrix = np.full((len(rigs), len(rigs)), np.nan)
    for train, test, value in zip(pairs.train, pairs.test, np.asarray(values, dtype=float)):
        matrix[index[str(train)], index[str(test)]] = value
    return matrix


def _runs(flags) -> list[tuple[int, int]]:
    """(start, stop) index ranges of the consecutive true entries of ``flags``."""
    runs, start = [], None
    for k, flag in enumerate(list(flags) + [False]):
        if flag and start is None:
            start = k
        elif not flag and start is not None:
            runs.append((start, k))
            start = None
    return runs


def _heatmap(ax, matrix: np.ndarray, rigs: list[str], control_rigs, cmap: str, norm: Normalize,
             fmt: str, title: str):
    """Draw ``matrix`` on ``ax`` (missing cells blank), annotate finite cells with ``fmt``, outline the control
    block; returns the image for a colour bar."""
    colormap = colormaps[cmap].with_extremes(bad="white")
    image = ax.imshow(np.ma.masked_invalid(matrix), cmap=colormap, norm=norm, interpolation="nearest")
    ticks = np.arange(len(rigs))
    ax.set_xticks(ticks, rigs, rotation=90, fontsize=8)
    ax.set_yticks(ticks, rigs, fontsize=8)
    ax.set_xlabel("test rig")
    ax.set_ylabel("training rig")
    ax.set_title(title, fontsize=10)
    size = 7 if len(rigs) <= 10 else 6
    for (row, col), value in np.ndenumerate(matrix):
        if np.isfinite(value):
            red, green, blue, _ = colormap(norm(value))
            ink = "black" if 0.299 * red + 0.587 * green + 0.114 * blue > 0.5 else "white"
            ax.text(col, row, fmt.format(value + 0.0), ha="center", va="center", fontsize=size, color=ink)
    runs = _runs(name in set(control_rigs) for name in rigs)
    for row0, row1 in runs:
        for col0, col1 in runs:
            ax.add_patch(Rectangle((col0 - 0.5, row0 - 0.5), col1 - col0, row1 - row0, fill=False,
                                   edgecolor="red", linewidth=2.0))
    return image


def _drop_heatmaps(model: str, pairs: PairPredictions, rigs: list[str], control_rigs) -> Figure:
    """Observed relative mAP drop (left) and the detector's own calibrated prediction (right) for every
    training x test rig pair, on one colour scale clipped to [min(0, p2), max(p98)] of the observed drops
    (cell labels keep the unclipped values); the control-rig block is outlined in red."""
    observed = _pair_matrix(pairs, pairs.delta, rigs)
    predicted = _pair_matrix(pairs, pairs.predicted, rigs)
    low, high = np.nanpercentile(observed, [2, 98])
    low = min(0.0, low)
    norm = Normalize(low, high if high > low else low + 1.0)
    fig = _figure((15.5, 7.0))
    axes = fig.subplots(1, 2)
    for ax, matrix, title in zip(axes, (observed, predicted), ("observed relative drop", "predicted drop (own fit)")):
        image = _heatmap(ax, matrix, rigs, control_rigs, "viridis", norm, "{:.2f}", title)
    fig.colorbar(image, ax=axes, shrink=0.8, extend="both", label="relative mAP drop (colour clipped)")
    fig.suptitle(f"{model}: relative mAP drop, training rig x test rig (control block outlined)")
    return fig


def _rank_error_heatmap(model: str, pairs: PairPredictions, rigs: list[str], control_rigs) -> Figure:
    """Rank error (predicted rank - observed rank of the drop among one training rig's test rigs, own fit) per
    training x test rig; a diverging scale centred at 0, positive = predicted to transfer better than observed."""
    errors = _pair_matrix(pairs, pairs.rank_error, rigs)
    bound = float(np.nanmax(np.abs(errors))) if np.isfinite(errors).any() else 0.0
    norm = Normalize(-max(bound, 1.0), max(bound, 1.0))
    fig = _figure((8.5, 7.5))
    ax = fig.subplots()
    image = _heatmap(ax, errors, rigs, control_rigs, "RdBu_r", norm, "{:.1f}",
                     "rank error = predicted rank - observed rank (rank 1 = largest drop)")
    fig.colorbar(image, ax=ax, shrink=0.8, label="rank error")
    fig.suptitle(f"{model}: per-training-rig rank error of the own fit")
    return fig


def _rho_text(rho: float) -> str:
    return f"{rho:.2f}" if np.isfinite(rho) else "n/a"


def _scatter_pairs(ax, pairs: PairPredictions, mask, color, labelled: bool = True) -> None:
    """Predicted vs observed drop of the pairs selected by ``mask``; control and held-out pairs as separate markers."""
    for control in (True, False):
        chosen = mask & (pairs.control == control)
        marker, label = _MARKERS[control]
        ax.scatter(pairs.delta[chosen], pairs.predicted[chosen], s=22 if control else 14, marker=marker,
                   color=color, alpha=0.9 if control else 0.55, edgecolors="black" if control else "none",
                   linewidths=0.5, label=f"{label} (n={int(chosen.sum())})" if labelled else "_nolegend_")


def _decorate(ax) -> None:
    ax.axline((0.0, 0.0), slope=1.0, color="grey", linestyle="--", linewidth=1.0, label="y = x")
    ax.set_xlabel("observed relative drop")
    ax.set_ylabel("predicted drop")
    ax.grid(alpha=0.3)


def _model_scatters(study: CalibrationStudy) -> Figure:
    """One panel per detector: its own fit's predicted drop against the observed drop, control pairs (squares,
    the fitted set) and held-out pairs (dots); the title gives the held-out Spearman rho."""
    count = len(study.models)
    columns = min(count, 2)
    rows = -(-count // columns)
    fig = _figure((6.0 * columns, 5.0 * rows))
    axes = np.atleast_1d(fig.subplots(rows, columns, squeeze=False)).ravel()
    for ax, model in zip(axes, study.models):
        everything = np.ones(len(model.pairs.delta), dtype=bool)
        _scatter_pairs(ax, model.pairs, everything, "tab:blue")
        _decorate(ax)
        fallback = " (fallback fit)" if model.fit.calibration.fallback else ""
        ax.set_title(f"{model.model}{fallback}: held-out rho = {_rho_text(model.heldout.rho)}", fontsize=10)
        ax.legend(fontsize=8, loc="upper left")
    for ax in axes[count:]:
        ax.set_visible(False)
    fig.suptitle("Own-fit calibration: predicted vs observed relative mAP drop")
    return fig


def _joint_scatter(study: CalibrationStudy) -> Figure:
    """The joint fit's predicted drop against the observed drop of every detector (one colour each), control
    pairs as squares and held-out pairs as dots; the legend gives each detector's held-out rho under the joint fit."""
    pairs = study.joint.pairs
    fig = _figure((8.0, 6.5))
    ax = fig.subplots()
    colours = colormaps["tab10"]
    handles = []
    for k, model in enumerate(study.joint.models):
        _scatter_pairs(ax, pairs, pairs.model == model.model, colours(k % 10), labelled=False)
        handles.append(Line2D([], [], linestyle="", marker="o", color=colours(k % 10),
                              label=f"{model.model}: held-out rho = {_rho_text(model.heldout.rho)}"))
    _decorate(ax)
    for control in (True, False):
        marker, label = _MARKERS[control]
        handles.append(Line2D([], [], linestyle="", marker=marker, color="grey", markeredgecolor="black" if control
                              else "grey", label=f"{label} (n={int(np.sum(pairs.control == control))})"))
    handles.append(Line2D([], [], color="grey", linestyle="--", label="y = x"))
    ax.legend(handles=handles, fontsize=8, loc="upper left")
    ax.set_title("Joint fit: predicted vs observed relative mAP drop", fontsize=11)
    return fig


def _figure(size: tuple[float, float]) -> Figure:
    """A stand-alone figure (no pyplot, no global backend): saved through its own Agg canvas."""
    return Figure(figsize=size, dpi=DPI, layout="constrained")


def _save(fig: Figure, path: Path) -> Path:
    fig.savefig(path, dpi=DPI)
    return path
