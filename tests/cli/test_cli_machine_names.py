"""Outputs name machines as the case's machine table does, by number and bus (`Case.machine_name`,
"G14 (bus 32)"), not by a bare number or index: `cct` and `screen` in text (the machines
that separate) and in JSON (their buses beside the numbers), and the legends of
`simulate --plot` (every machine of a small case; the separated ones of a large case, the
rest counted and said to be the machines that did not separate).

The expected names are built from the case's machine table (``machines.number``,
``machines.bus``), never typed in: which machines separate is the run's (Kundur's fault at
bus 3: area 1's G1, G2; miniWECC's fault on line 83-33: Colstrip, G14)."""

import json

import matplotlib.pyplot as plt
import pytest
from click.testing import CliRunner

from stabctl.cli import main
from stabctl.io import load_case
from stabctl.plotting import figures


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def table_name(case, number: int) -> str:
    """The name read off the case's machine table: G<number> (bus <bus>)."""
    (row,) = [k for k, n in enumerate(case.machines.number) if int(n) == int(number)]
    return f"G{int(case.machines.number[row])} (bus {int(case.machines.bus[row])})"


def table_bus(case, number: int) -> int:
    return int(case.machines.bus[list(case.machines.number.astype(int)).index(int(number))])


@pytest.mark.parametrize(
    "name, fault, far_bus, tol_ms",
    [("kundur", 3, 101, 1), ("miniwecc", 83, 33, 5)],
    ids=["kundur-3-101", "miniwecc-83-33"],
)
def test_cct_names_the_machines_that_separate(name, fault, far_bus, tol_ms):
    """`stabctl cct`: the JSON keeps ``separated_machines`` (numbers) and adds
    ``separated_buses`` (their buses, the table's); the text names each machine
    "G<number> (bus <bus>)" in the line of the machines that lose synchronism.  miniWECC's
    G14 sits at bus 32: a number printed as a bus (or the reverse) would not pass."""
    case = load_case(name)
    args = ("cct", name, "--fault", fault, "--far-bus", far_bus, "--tol-ms", tol_ms)
    res = run(*args, "--json")
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    lost = d["separated_machines"]
    assert lost and all(isinstance(m, int) for m in lost)  # numbers as before
    assert d["separated_buses"] == [table_bus(case, m) for m in lost]
    text = run(*args)
    assert text.exit_code == 0, text.output
    names = ", ".join(table_name(case, m) for m in lost)
    assert f"machine(s) {names} lose synchronism when cleared at" in text.stdout


def test_screen_names_the_machines_that_separate(tmp_path):
    """`stabctl screen kundur --buses 3,101`: the row of each fault with a CCT names its
    separated machines "G<number> (bus <bus>)" (not a Python list of numbers); the JSON rows
    keep ``separated`` and add ``separated_buses``; a robust fault names none."""
    case = load_case("kundur")
    out = tmp_path / "s.jsonl"
    args = ("screen", "kundur", "--buses", "3,101", "--workers", 1, "--out", out)
    res = run(*args, "--json")
    assert res.exit_code == 0, res.output
    rows = {r["bus"]: r for r in json.loads(res.stdout)}
    lost = rows[3]["separated"]
    assert lost and rows[3]["separated_buses"] == [table_bus(case, m) for m in lost]
    assert "separated" not in rows[101] and "separated_buses" not in rows[101]
    text = run(*args)  # resumed from --out: the same rows
    assert text.exit_code == 0, text.output
    (line,) = [x for x in text.stdout.splitlines() if x.startswith("bus 3 ")]
    assert line.endswith("  " + ", ".join(table_name(case, m) for m in lost)), line
    assert "[" not in line


@pytest.fixture
def figures_made(monkeypatch):
    """The figures the plotting functions save (kept open to read their legends, and
    saved as before)."""
    out = []
    save = figures.save_figure

    def keep(fig, path):
        out.append(fig)
        save(fig, path)

    monkeypatch.setattr(figures, "save_figure", keep)
    yield out
    for fig in out:
        plt.close(fig)


def legend(ax) -> list[str]:
    return [t.get_text() for t in ax.get_legend().get_texts()]


def simulate_plot(tmp_path, name, fault, far_bus, cycles):
    """`stabctl simulate NAME ... --stop-at-separation --json --plot`: (its JSON, the file)."""
    path = tmp_path / f"{name}.png"
    res = run(
        "simulate", name, "--fault", fault, "--far-bus", far_bus, "--clear-cycles", cycles,
        "--stop-at-separation", "--json", "--plot", path,
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    assert path.stat().st_size > 0
    return json.loads(res.stdout)


def test_simulate_plot_legend_names_every_machine_of_a_small_case(tmp_path, figures_made):
    """Kundur (4 machines, at most 10 named): the speed and angle panels' legends name
    every machine "G<number> (bus <bus>)" (G3, G4 sit at buses 11, 12), and the title
    names the separated ones the same way."""
    case = load_case("kundur")
    d = simulate_plot(tmp_path, "kundur", 3, 101, 21)
    (fig,) = figures_made
    names = [table_name(case, m) for m in case.machines.number]
    for ax in fig.axes[:2]:
        assert legend(ax) == [*names, "loss of synchronism"]
    lost = ", ".join(table_name(case, m) for m in d["separated_machines"])
    assert d["separated_machines"] and fig.axes[0].get_title().endswith(f"machine(s) {lost}")


def test_simulate_plot_legend_of_a_large_case_says_what_the_others_are(tmp_path, figures_made):
    """miniWECC (34 machines, more than 10): the separated machine is drawn thick and named
    "G<number> (bus <bus>)" in the legend and at the end of its trace; the legend entry of
    the rest says how many they are and what they are (not "other 33 machines (thin)",
    whose grey swatch matched none of their coloured traces)."""
    case = load_case("miniwecc")
    d = simulate_plot(tmp_path, "miniwecc", 83, 33, 6)
    lost = d["separated_machines"]
    (fig,) = figures_made
    for ax in fig.axes[:2]:
        named = [table_name(case, m) for m in lost]
        others = len(case.machines) - len(lost)
        assert legend(ax) == [
            *named,
            f"other {others} machines not separated (thin, one colour each)",
            "loss of synchronism",
        ]
        assert set(named) <= {a.get_text() for a in ax.texts}  # at the traces' ends


def test_simulate_json_gives_the_buses_of_the_machines_that_separate():
    """`stabctl simulate --json` of miniWECC's line 83-33 cleared after 12 cycles (beyond
    its 4.6-cycle CCT): ``separated_machines`` keeps the numbers and ``separated_buses``
    (missing before) gives their buses, the table's, as `cct --json` does."""
    case = load_case("miniwecc")
    args = ("simulate", "miniwecc", "--fault", 83, "--far-bus", 33, "--clear-cycles", 12)
    res = run(*args, "--tf", 3, "--json")
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    lost = d["separated_machines"]
    assert lost and d["separated_buses"] == [table_bus(case, m) for m in lost]


def test_a_highlighted_machine_that_did_not_separate_is_said_so(tmp_path, figures_made):
    """The paper's Case 2 figure (miniWECC, 34 machines) highlights G13 and G14, drawn
    thick; only G14 separates without storage and none with it, yet the legend named both
    beside "other 32 machines not separated", as if G13 had.  A highlighted machine that
    did not separate in the panel's run is named ", not separated" there."""
    from stabctl.dynamics.driver import Simulator
    from stabctl.stability.cct import LineFault
    from stabctl.storage.devices import uniform_fleet

    case = load_case("miniwecc")
    sim = Simulator(case)
    fault = LineFault(83, 33, 1.0).events(6 / 60)
    without = sim.run(fault, t_end=4.0, stop_at_separation=True)
    with_ = sim.run(fault, t_end=4.0, storage=uniform_fleet(case, 5))
    lost = {int(m) for m in without.separated}
    assert lost and not with_.separated and 13 not in lost
    figures.storage_case_figure(
        without, with_, tmp_path / "c2.png", "Case 2", case=case, highlight=(13, 14)
    )
    (fig,) = figures_made
    for ax, res in zip(fig.axes[:2], (without, with_)):
        gone = {int(m) for m in res.separated}
        for m in sorted({13, *lost}):
            said = table_name(case, m) + ("" if m in gone else ", not separated")
            assert said in legend(ax), (m, legend(ax))
