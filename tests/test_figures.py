"""The figures name what a reader needs: a large case's bus voltages name the buses that
fall lowest (a bolted fault holds its own bus at 0 pu), the mode-shape and participation
figures carry a legend of the coherent areas."""

import matplotlib.pyplot as plt
import numpy as np
import pytest

import stabctl
from stabctl.plotting import figures
from stabctl.studies.cases import CASE2


@pytest.fixture
def kept(monkeypatch):
    """The figures a plotting function saves, kept open instead of written."""
    out = []
    monkeypatch.setattr(figures, "save_figure", lambda fig, path: out.append(fig))
    yield out
    for fig in out:
        plt.close(fig)


def legend_texts(fig_or_ax) -> list[str]:
    legends = fig_or_ax.legends if hasattr(fig_or_ax, "legends") else [fig_or_ax.get_legend()]
    return [t.get_text() for lg in legends if lg for t in lg.get_texts()]


def test_large_case_bus_voltages_name_the_deepest_buses(kept):
    case = stabctl.load_case(CASE2.case)
    res = stabctl.Simulator(case).run(CASE2.fault.events(6 / case.freq_hz), t_end=1.3)
    figures.simulation_overview(res, "unused.png", case=case)
    names = legend_texts(kept[0].axes[2])
    assert names[0] == f"other {case.n_bus - 3} buses (thin)"
    # the faulted bus first: a bolted fault holds it at 0 pu
    assert names[1] == f"B{CASE2.fault.bus} (min 0.00 pu)" and len(names) == 4
    deepest = sorted(res.vmag.min(axis=0))[:3]
    shown = [float(n.split("min ")[1].split(" pu")[0]) for n in names[1:]]
    np.testing.assert_allclose(shown, deepest, atol=5e-3)


def test_mode_figures_have_an_area_legend(kept):
    ma = stabctl.modal_analysis(stabctl.linearise(stabctl.Simulator(stabctl.load_case("kundur"))))
    em = list(ma.electromechanical)
    figures.mode_shape_compass(ma, em, "unused.png")
    figures.participation_bars(ma, em, "unused.png")
    for fig in kept:  # Kundur's two areas of two machines each (Kundur 12.8)
        assert legend_texts(fig) == ["area 1 (2 machines)", "area 2 (2 machines)"]


def test_a_screening_of_some_buses_maps_them_readably(kept):
    """`stabctl screen --buses` of 6 of miniWECC's 122 buses: the others drawn as small grey
    points, every screened bus labelled, the title saying how many, the view zoomed to
    the screened buses (their spectral-layout box); a whole screening keeps the whole
    network and labels the ten most critical."""
    from stabctl.plotting.layout import spectral_layout

    case = stabctl.load_case("miniwecc")
    buses = [int(b) for b in case.buses.number[:: case.n_bus // 6][:6]]
    rows = [
        {"bus": b, "far_bus": None, "verdict": "cct", "cct_s": 0.1 + 0.01 * k}
        for k, b in enumerate(buses)
    ]
    figures.screening_map(case, rows, "unused.png")
    ax = kept[-1].axes[0]
    assert f"each of 6 of {case.n_bus} buses" in ax.get_title()
    assert sorted(int(n) for t in ax.texts for n in t.get_text().split(", ")) == sorted(buses)
    assert "not screened" in legend_texts(ax)
    xy = spectral_layout(case)[case.bus_indices(buses)]
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 < xy[:, 0].min() and xy[:, 0].max() < x1 and y0 < xy[:, 1].min()
    whole = spectral_layout(case)
    assert (x1 - x0) * (y1 - y0) < np.ptp(whole[:, 0]) * np.ptp(whole[:, 1])  # zoomed in
    every = [
        {"bus": int(b), "far_bus": None, "verdict": "cct", "cct_s": 0.1 + 1e-3 * k}
        for k, b in enumerate(case.buses.number)
    ]
    figures.screening_map(case, every, "unused.png")
    ax = kept[-1].axes[0]
    assert ax.get_title().endswith("at each bus")
    named = [int(n) for t in ax.texts for n in t.get_text().split(", ")]
    assert sorted(named) == sorted(int(r["bus"]) for r in every[:10])  # the ten most critical


def test_a_screening_map_draws_the_branch_faults_and_their_verdicts(kept):
    """Round 42: `screen --lines --plot` drew the bus faults only, so WECC-179's 13 N-1
    insecure lines and its islanding trips showed nowhere on the map.  Each branch fault
    is now a square at its branch's middle (the mean of its two buses' places), on the
    bus faults' colour scale, robust ones open and N-1 insecure ones red crosses, each
    kind named in the legend, the title counting them."""
    from stabctl.plotting.layout import spectral_layout

    case = stabctl.load_case("kundur")
    rows = [
        {"bus": 3, "far_bus": None, "verdict": "cct", "cct_s": 0.238},
        {"bus": 3, "far_bus": 101, "verdict": "cct", "cct_s": 0.154},
        {"bus": 13, "far_bus": 120, "verdict": "above t_max", "t_max_s": 0.5},
        {"bus": 2, "far_bus": 20, "verdict": "N-1 insecure"},
    ]
    figures.screening_map(case, rows, "unused.png")
    ax = kept[-1].axes[0]
    assert "and of 3 branch fault(s) (squares, mid-branch)" in ax.get_title()
    assert legend_texts(ax) == [
        "not screened",
        "CCT above the search limit 0.5 s (robust) (branch fault)",
        "N-1 insecure: unstable even when cleared at once (CCT 0) (branch fault)",
    ]
    xy = spectral_layout(case)
    red = next(c for c in ax.collections if c.get_label().startswith("N-1 insecure"))
    np.testing.assert_allclose(red.get_offsets()[0], xy[case.bus_indices([2, 20])].mean(axis=0))
    coloured = [c for c in ax.collections if c.get_array() is not None and len(c.get_array())]
    cycles = sorted(float(v) for c in coloured for v in c.get_array())
    np.testing.assert_allclose(cycles, [0.154 * 60, 0.238 * 60])  # one scale for both
    assert {c.norm.vmin for c in coloured} == {0.154 * 60}


def test_a_screening_map_rings_unconverged_ccts_and_keeps_its_legend_off_the_markers(kept):
    """Round 45: a CCT not converged in the run's end (cleared at it, a longer run loses
    synchronism) was drawn as any CCT, and the legend, inside the axes at their lower
    right, could cover a marker.  Such a row now has a magenta ring, named in the legend,
    and the legend sits below the axes, clear of every marker."""
    case = stabctl.load_case("kundur")
    late = {"t_end_s": 11.0, "t_separation_s": 6.07}
    rows = [
        {"bus": 3, "far_bus": None, "verdict": "cct", "cct_s": 0.238},
        {"bus": 101, "far_bus": None, "verdict": "cct", "cct_s": 0.2, "run_end_check": late},
        {"bus": 13, "far_bus": 120, "verdict": "above t_max", "t_max_s": 0.5},
        {"bus": 2, "far_bus": 20, "verdict": "N-1 insecure"},
    ]
    figures.screening_map(case, rows, "unused.png")
    fig = kept[-1]
    ax = fig.axes[0]
    ring = next(c for c in ax.collections if c.get_label().startswith("CCT not converged"))
    xy = stabctl.plotting.layout.spectral_layout(case)
    np.testing.assert_allclose(ring.get_offsets(), xy[case.bus_indices([101])])
    fig.canvas.draw()
    box = ax.get_legend().get_window_extent()
    assert box.y1 <= ax.get_window_extent().y0  # below the axes: over no marker


@pytest.mark.parametrize("suffix", ["png", "pdf", "svg"])
def test_a_figure_written_twice_is_the_same_bytes(suffix, tmp_path, monkeypatch):
    """`simulate --plot r.pdf` (or .svg, and `screen --plot s.svg`) differed from run to
    run in its date of writing (the PDF's /CreationDate, the SVG's <dc:date>) and the
    SVG's random element ids: the one figure writer stores no date and salts the ids with
    a constant, so that the same figure gives the same bytes at any time, whatever
    SOURCE_DATE_EPOCH says."""

    def draw():
        fig, ax = plt.subplots()
        ax.plot([0, 1], [1, 2], label="a")
        ax.fill_between([0, 1], [0, 1], alpha=0.3)  # clipped: the SVG names a clip path
        ax.set_title("two writes")
        ax.legend()
        return fig

    written = []
    for epoch in ("0", "1000000000", None):  # other times of writing
        if epoch is None:
            monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)
        else:
            monkeypatch.setenv("SOURCE_DATE_EPOCH", epoch)
        path = tmp_path / f"{len(written)}.{suffix}"
        figures.save_figure(draw(), path)
        written.append(path.read_bytes())
    assert written[0] == written[1] == written[2]


def test_screening_map_labels_of_buses_drawn_on_one_another_are_joined():
    """A subset's map drew 1002 and 1032 of the 240-bus WECC case on one another (the
    layout puts them 1e-3 of its extent apart): buses within 3 % of the drawing share a
    label, the others keep their own."""
    import numpy as np

    from stabctl.plotting.figures import _label_groups

    pts = np.array([[0.0, 0.0], [1e-3, 0.0], [0.5, 0.5], [1.0, 1.0]])
    groups = _label_groups(pts, [1002, 1032, 1001, 2130], pts)
    assert [names for _, names in groups] == ["1002, 1032", "1001", "2130"]
    assert np.array_equal(groups[0][0], pts[0])
