"""A network of several islands has one centre of inertia per island (paper eq. 40 over the
machines each machine is connected to): the loss-of-synchronism verdict and the storage
controllers' relative speeds are judged there.  Conservation: in each island the
inertia-weighted relative values sum to zero; in a connected network every per-island
figure is the system's, to the last digit."""

from pathlib import Path

import numpy as np
import pytest

from stabctl.dynamics.coi import (
    coi_inertia,
    coi_of_islands,
    coi_of_rest,
    coi_value,
    island_coi,
)
from stabctl.dynamics.driver import separated_group
from stabctl.errors import InputError
from stabctl.estimation.models import machine_models
from stabctl.estimation.pmu import machine_pmus
from stabctl.io import load_case
from stabctl.io.psse import load_psse
from stabctl.network.topology import bus_islands, machine_islands
from stabctl.storage.control import relative_speeds
from stabctl.storage.devices import pack, uniform_fleet

DATA = Path(__file__).parents[1] / "data" / "psse"
RNG = np.random.default_rng(29)
ISLAND = np.array([0, 0, 1, 1, 1])
M = np.array([5850.0, 2000.0, 3000.0, 1000.0, 500.0])  # MW s


@pytest.fixture(scope="module")
def kundur():
    return load_case("kundur")


def test_a_connected_case_is_one_island(kundur):
    assert np.all(bus_islands(kundur) == 0)
    assert list(machine_islands(kundur)) == [0, 0, 0, 0]


def split_kundur(kundur):
    """Kundur's areas join at buses 3 and 13 only (lines 3-101 and 13-101 through the
    midpoint bus 101): the case with both opened (PST's open-branch reactance)."""
    br = kundur.branches
    tie = ((br.from_bus == 3) & (br.to_bus == 101)) | ((br.from_bus == 13) & (br.to_bus == 101))
    tie |= ((br.to_bus == 3) & (br.from_bus == 101)) | ((br.to_bus == 13) & (br.from_bus == 101))
    assert tie.sum() >= 2
    return kundur.replace(branches=br.replace(x=np.where(tie, 1e7, br.x)))


def test_opening_the_tie_lines_splits_kundur_into_its_two_areas(kundur):
    """Machines 1, 2 and 11, 12 form two islands."""
    assert list(machine_islands(split_kundur(kundur))) == [0, 0, 1, 1]


def test_speed_estimators_refuse_islands_and_infinite_buses(kundur):
    """The estimators' COI is one system's: a case in two islands is refused by name, as
    is an infinite bus (no swing equation to filter)."""
    split = split_kundur(kundur)
    with pytest.raises(InputError, match=r"'kundur': its machines lie in 2 islands"):
        machine_models(split, machine_pmus(split))
    smib = load_psse(DATA / "smib_v33.raw", DATA / "smib.dyr")
    with pytest.raises(InputError, match=r"machine\(s\) \[2\] are infinite buses"):
        machine_models(smib, machine_pmus(smib))


def test_infinite_bus_weights_stay_in_its_island():
    H = np.array([6.5, 0.0, 6.5, 6.175])
    mva = np.full(4, 900.0)
    one = coi_inertia(H, mva)  # one island: the infinite bus is the COI
    assert list(one) == [0.0, 1.0, 0.0, 0.0]
    two = coi_inertia(H, mva, np.array([0, 1, 0, 1]))
    assert list(two) == [5850.0, 1.0, 5850.0, 0.0]  # island 0 keeps H * MVA


def test_island_coi_sums_to_zero_in_each_island_and_is_the_system_coi_when_connected():
    x = RNG.normal(size=(7, M.size))
    rel = x - coi_of_islands(x, M, ISLAND)
    for k in (0, 1):
        assert np.allclose(rel[:, ISLAND == k] @ M[ISLAND == k], 0.0, atol=1e-9)  # of ~1e4
    coi, Mk = island_coi(x[0], M, ISLAND)
    assert np.allclose(coi, coi_of_islands(x[0], M, ISLAND), rtol=0, atol=1e-14)
    assert list(Mk) == [7850.0, 7850.0, 4500.0, 4500.0, 4500.0]
    one = np.zeros(M.size, np.int64)
    coi1, M1 = island_coi(x[0], M, one)
    assert np.all(coi1 == coi_value(x[0], M)) and np.all(M1 == M.sum())  # same digits


def test_storage_relative_speeds_are_against_their_island(kundur):
    """Device d sits at machine d's HV bus (Kundur's uniform fleet): with machines 1, 2 and
    3, 4 in two islands each reads its own island's COI (or the rest of it)."""
    sa = pack(uniform_fleet(kundur, 5), kundur, np.arange(kundur.n_bus))
    mac = np.asarray(sa.mac)
    nm, island, Mk = 4, np.array([0, 0, 1, 1]), M[:4]
    w = 1 + RNG.normal(scale=1e-3, size=nm)
    x = np.r_[np.zeros(nm), w]
    out = np.empty(mac.size)
    relative_speeds(x, nm, Mk, island, sa, out)
    expected = w - coi_of_islands(w, Mk, island)
    assert np.allclose(out, expected[mac], rtol=0, atol=1e-15)
    rest = sa._replace(rest=True)
    relative_speeds(x, nm, Mk, island, rest, out)
    partner = np.array([1, 0, 3, 2])  # the rest of a two-machine island is the other one
    assert np.allclose(out, (w - w[partner])[mac], rtol=0, atol=1e-15)
    rest_coi = coi_of_rest(w[None], Mk, mac, island)[0]  # SIME's Table 3 reconstruction
    assert np.allclose(out, w[mac] - rest_coi, rtol=0, atol=1e-15)


def test_separated_group_is_found_in_the_island_that_lost_synchronism():
    """Island 1 (machines 3, 4, 5) has machine 5 pole-slipping; island 0 sits at a
    different but steady angle, which one COI would have read as the largest gap."""
    delta = np.array([10.0, 10.1, 0.0, 0.1, 4.0])
    assert list(separated_group(delta, M)) == [2, 3, 4]  # one COI: the whole island
    assert list(separated_group(delta, M, ISLAND)) == [4]


def test_a_trip_that_islands_a_load_bus_sheds_its_load_as_pss_e(kundur):
    """Tripping Kundur's transformer 3-4 cuts load bus 4 (976 MW + j100 Mvar, half of it
    constant current) from every generator.  PSS/E de-energises such an island and sheds
    its load; so does stabctl: the run goes on, bus 4's voltage is 0 from the trip, the
    result names the bus and the load shed, and the machines see the lost load (area 1
    accelerates ahead of area 2); a run that islands nothing has no such record."""
    from stabctl.dynamics.driver import Simulator
    from stabctl.dynamics.events import LineTrip

    sim = Simulator(kundur)
    res = sim.run([LineTrip(3, 4, 1.0)], 3.0)
    assert res.meta["islanded"] == [{"t_s": 1.0, "buses": [4], "load_shed_pu": [9.76, 1.0]}]
    b4 = list(res.buses).index(4)
    after = res.t > 1.0
    assert np.max(res.vmag[after, b4]) < 1e-6 and res.vmag[0, b4] > 0.9
    area1 = [list(res.machines).index(m) for m in (1, 2)]
    assert np.all(res.speed[-1, area1] > res.speed[-1, [2, 3]])  # area 1 lost its load
    flat = sim.run([], 3.0)
    assert "islanded" not in flat.meta
