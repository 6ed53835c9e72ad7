"""The dynamic model of a case: state layout, initialisation from the power flow, network
stages, and one evaluation of all right-hand sides (PST flag 1, network solution, flag 2).

This is the single implementation of the multi-machine equations: the time-domain
integrator, the linearisation, the CCT search and the estimators all call
`DynamicModel.evaluate`.  Source: PSTess 1.1 `s_simu.m` (order of model calls),
docs/pst_models.md sections 1-7.
"""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass, field, replace
from typing import NamedTuple

import numpy as np
from numba import types

from stabctl._jit.address import address_of, by_address
from stabctl._jit.arrays import SMALL_MATVEC, assign, dot, magnitude, matvec
from stabctl._jit.borrow import borrowed
from stabctl._jit.decorators import kernel, njit
from stabctl.case import BranchTable, BusTable, Case
from stabctl.case.events import FAULT_B
from stabctl.dynamics.bounded import BoundedCache
from stabctl.dynamics.coi import coi_inertia
from stabctl.errors import CaseError, InputError, SimulationError, advice
from stabctl.models import converters as conv
from stabctl.models import exciters as exc
from stabctl.models import governors as gov
from stabctl.models import machines as mac
from stabctl.models import motors as mot
from stabctl.models import pss as pss_
from stabctl.models import shafts as shaft
from stabctl.models import shunts as shunt
from stabctl.models import svcs as svc
from stabctl.network import solution
from stabctl.network import switched_shunts as sws
from stabctl.network.solution import (
    NEWTON_MAX_ITER,
    NonConformingLoads,
    ReducedNetwork,
    kept_loads,
    newton_step,
    reduce_network,
    solve_nc,
)
from stabctl.network.solution import L as LOAD
from stabctl.network.topology import OPEN_X, bus_islands, machine_islands

#: largest |derivative| at t = 0 of an equilibrium (DynamicModel.check_equilibrium)
EQUILIBRIUM_TOL = 1e-8


@dataclass(frozen=True)
class OperatingPoint:
    """Solved power flow as the dynamic model needs it, arrays of shape (n_bus,):
    V complex bus voltage (pu), S_gen and S_load complex generation and load (pu)."""

    V: np.ndarray
    S_gen: np.ndarray
    S_load: np.ndarray

    @classmethod
    def from_bus_matrix(cls, bus: np.ndarray) -> OperatingPoint:
        """From a solved PST bus matrix (columns: number, |V|, angle deg, Pg, Qg, Pl, Ql...)."""
        bus = np.asarray(bus, float)
        V = bus[:, 1] * np.exp(1j * np.deg2rad(bus[:, 2]))
        return cls(V=V, S_gen=bus[:, 3] + 1j * bus[:, 4], S_load=bus[:, 5] + 1j * bus[:, 6])


@dataclass(frozen=True)
class StageConfig:
    """Network configuration of one interval (hashable; built by `stabctl.dynamics.events`).

    faults: (bus index, shunt admittance) pairs: PST's sw_con fault replaces the bus shunt
        (pstess; and a bolted fault under both conventions, where the shunt is immaterial);
        under ieee a fault through an impedance adds to it (a fault does not disconnect the
        bus's capacitor banks: as ANDES's Fault and PSS/E);
    opened: branch rows opened by PST's x = 1e7 (line charging stays connected under the
        pstess conventions, as PST; removed under ieee: both breakers open de-energise it);
    fault_feeds: (branch row, far-end bus number, still_faulted) for a line cleared at the
        near end: a copy of the line (with its charging) feeds a fault node from the far
        end until the far end clears too (PST y_switch; then, under ieee, without it);
    tripped_machines: machine indices disconnected; tripped_converters: converter indices
    disconnected (they inject nothing, their states stand still); load_steps: (bus index,
    admittance);
    motors_on: motor indices in service (switched on by events; `stabctl.models.motors`);
    playback: (machine index, dV, df) of playback sources whose targets moved from their
    initial E' and speed 1 pu (a Playback event);
    vref_steps, pref_steps: (machine index, change) of the machines whose exciter's voltage
    reference (pu) or governor's power reference (pu on the machine base) moved from its
    initial value (VrefStep / PrefStep events: PSS/E's change of VREF / PREF).
    """

    faults: tuple = ()
    opened: tuple = ()
    fault_feeds: tuple = ()
    tripped_machines: tuple = ()
    tripped_converters: tuple = ()
    load_steps: tuple = ()
    motors_on: tuple = ()
    playback: tuple = ()
    vref_steps: tuple = ()
    pref_steps: tuple = ()


@dataclass
class Layout:
    """Slices of the flat state vector: machines (6, n_mac), exciters (exc_rows, n_exc),
    pss (pss_rows, n_pss), governors (tg_rows, n_tg), converters (conv.N_STATES, n_ibr),
    shafts (shaft.N_STATES, n_shaft), motors (mot.N_STATES, n_motor), switched shunts'
    memory (shunt.N_STATES, n_swsh), static var compensators (svc.N_STATES, n_svc), each
    stored state-major; the rows are the most slots
    any exciter / PSS / governor type of the case uses."""

    n_mac: int
    n_exc: int
    n_pss: int
    n_tg: int
    exc_rows: int = 3
    pss_rows: int = 3
    tg_rows: int = 3
    n_ibr: int = 0
    n_shaft: int = 0
    n_motor: int = 0
    n_swsh: int = 0
    n_svc: int = 0
    blocks: dict = field(default_factory=dict)

    def __post_init__(self):
        start = 0
        for name, rows, n in (
            ("mac", 6, self.n_mac),
            ("exc", self.exc_rows, self.n_exc),
            ("pss", self.pss_rows, self.n_pss),
            ("tg", self.tg_rows, self.n_tg),
            ("ibr", conv.N_STATES, self.n_ibr),
            ("shaft", shaft.N_STATES, self.n_shaft),
            ("motor", mot.N_STATES, self.n_motor),
            ("swsh", shunt.N_STATES, self.n_swsh),
            ("svc", svc.N_STATES, self.n_svc),
        ):
            self.blocks[name] = (slice(start, start + rows * n), (rows, n))
            start += rows * n
        self.size = start

    def view(self, x, name):
        sl, shape = self.blocks[name]
        return x[sl].reshape(shape)


#: Model conventions: "ieee" (default; limiters as IEEE Std 421.5-2016, results converge
#: as the step shrinks) and "pstess" (PSTess 1.1 bit for bit, quirks included).
CONVENTIONS = ("ieee", "pstess")


def check_conventions(conventions: str) -> str:
    """Return `conventions` if it is one of CONVENTIONS, else raise InputError."""
    if conventions not in CONVENTIONS:
        raise InputError(
            f"conventions must be one of {', '.join(CONVENTIONS)}, got {conventions!r}"
        )
    return conventions


#: reduced network stages a model keeps (`DynamicModel.network`): a run uses one per
#: interval between events (a CCT probe 3, the pre-fault one shared), a screening worker's
#: model would otherwise keep every fault's (ACTIVSg2000: about 11 MB a stage)
STAGES_KEPT = 8


class DynamicModel:
    """Dynamic model of a case at an operating point.

    Args:
        case: the case; op: its solved power flow; injection_buses: extra bus numbers to
            keep in the reduced network for device injections (storage); conventions:
            "ieee" (limiters as IEEE Std 421.5-2016) or "pstess" (PSTess 1.1 exactly,
            docs/pst_models.md 2.1); docs/conventions.md lists the differences.
    Raises:
        CaseError: unsupported models, limits violated at the initial point, a machine bus
            without generation; InputError: unknown conventions.
    """

    def __init__(
        self, case: Case, op: OperatingPoint, injection_buses=(), conventions: str = "ieee"
    ):
        self.case, self.op = case, op
        self.conventions = check_conventions(conventions)
        self.mp = mac.machine_params(case)
        self.ep = exc.exciter_params(case)
        self.pp = pss_.pss_params(case, np.abs(op.V[self.mp.bus_idx]))
        self.gp = gov.governor_params(case)
        self.cp = conv.converter_params(case, op.V, op.S_gen)
        self.tp = shaft.shaft_params(case)
        self.mo = mot.motor_params(case)
        self.sv = svc.svc_params(case, op.V, op.S_gen)
        self.layout = Layout(
            self.mp.n,
            self.ep.n,
            self.pp.n,
            self.gp.n,
            self.ep.n_slots(),
            self.pp.n_slots(),
            self.gp.n_slots(),
            self.cp.n,
            self.tp.n,
            self.mo.n,
            len(case.switched_shunts),
            self.sv.n,
        )
        self._setup_loads(injection_buses)
        self._stage_cache: BoundedCache[ReducedNetwork] = BoundedCache(STAGES_KEPT)
        self._initialise()

    # -- loads and kept buses ---------------------------------------------------------
    def _setup_loads(self, injection_buses):
        case, op = self.case, self.op
        V0 = np.abs(op.V)
        lc = case.loads.matrix()
        frac = np.zeros((case.n_bus, 4))
        if lc.size:
            frac[case.bus_indices(lc[:, 0])] = lc[:, 1:5]
        has_mac = np.zeros(case.n_bus, bool)
        has_mac[self.mp.bus_idx] = True
        S_free = op.S_gen
        cp = self.cp
        if cp.n:  # the converters' shares of the generation at buses without machine
            S_conv = np.zeros(case.n_bus, complex)
            np.add.at(S_conv, cp.bus_idx, cp.P0 + 1j * cp.Q0)
            S_free = op.S_gen - S_conv
        sv = self.sv
        # the compensators' shares of the reactive generation: their susceptance B0 at
        # their bus, beside (not netted with) the bus's load
        y_svc = np.zeros(case.n_bus, complex)
        np.add.at(y_svc, sv.bus_idx, 1j * sv.B0)
        S_free = S_free - 1j * y_svc.imag * V0**2
        _warn_netted(case, has_mac, S_free)
        S_L = op.S_load - np.where(has_mac, 0.0, S_free)  # generation without machine
        fP, fQ, fIP, fIQ = frac.T
        S_Z = (1 - fP - fIP) * S_L.real + 1j * (1 - fQ - fIQ) * S_L.imag
        # the switched shunts at the level they start at (the power flow's, `Simulator`)
        self.y_load = np.conj(S_Z) / V0**2 + sws.bus_admittances(case) + y_svc
        extra = case.bus_indices(list(injection_buses)) if len(injection_buses) else []
        nc = np.asarray(case.bus_indices(lc[:, 0]) if lc.size else [], int)
        # the converters' buses and their plant controls' line ends (REPCA1)
        sw, inj = case.switched_shunts, case.injections
        self.sw_bus = np.asarray(case.bus_indices(sw.bus) if len(sw) else [], int)
        # the fixed injections (case.injections: HVDC converters' set points): constant
        # power at their kept buses, as in the power flow (which books them in neither
        # the generation nor the load)
        inj_bus = np.asarray(case.bus_indices(inj.bus) if len(inj) else [], int)
        S_inj = np.zeros(case.n_bus, complex)
        np.add.at(S_inj, inj_bus, inj.p + 1j * inj.q)
        ends = np.concatenate(
            [cp.bus_idx, cp.bus1_idx, cp.bus2_idx, self.mo.bus_idx, self.sw_bus, inj_bus]
            + [sv.bus_idx]
        )
        ends = ends.astype(int)
        self.nc_idx = np.unique(np.concatenate([nc, np.asarray(extra, int), ends])).astype(int)
        rows_of = ((cp.pos, cp.bus_idx), (cp.pos1, cp.bus1_idx), (cp.pos2, cp.bus2_idx))
        for pos, rows in (*rows_of, (self.mo.pos, self.mo.bus_idx), (sv.pos, sv.bus_idx)):
            pos[:] = np.searchsorted(self.nc_idx, rows)
        i = self.nc_idx
        S_P = fP[i] * S_L[i].real + 1j * fQ[i] * S_L[i].imag - S_inj[i]
        S_I = fIP[i] * S_L[i].real + 1j * fIQ[i] * S_L[i].imag
        self.nc = NonConformingLoads(S_P=S_P, I0=S_I / V0[i], Y_low=np.conj(S_P + S_I) / V0[i] ** 2)

    # -- network stages ---------------------------------------------------------------
    def subtransient_time_constants(self, net: ReducedNetwork, below: float) -> np.ndarray:
        """Each machine's shortest subtransient time constant in stage `net` (s;
        `MachineParams.subtransient_time_constants` behind the reactance it sees there,
        `solution.external_impedance`), for the machines whose short-circuit one (T"do
        x"d/x'd, the shortest any network gives) is below `below` (s); inf for the
        others and for tripped machines.

        Parameters
        ----------
        net : ReducedNetwork
            A stage of this model (`network`).
        below : float
            The bound, s (a run's step: only shorter ones matter).

        Returns
        -------
        ndarray, shape (n_mac,)
        """
        mp = self.mp
        out = np.full(mp.n, np.inf)
        rows = np.flatnonzero(self.short_circuit_time_constants < below)
        if rows.size:
            z = solution.external_impedance(net, rows)
            xe = np.full(mp.n, np.inf)
            xe[rows] = np.where(np.isnan(z), np.inf, z.imag / mp.mac_pot[rows])
            out[rows] = mp.subtransient_time_constants(xe)[rows]
        return out

    @functools.cached_property
    def short_circuit_time_constants(self) -> np.ndarray:
        """Each machine's subtransient time constant at a bolted fault at its terminal
        (s; T"do x"d/x'd or the q axis's, the shorter; inf where not subtransient): the
        shortest any network gives it, taken once per model (every run asks)."""
        return self.mp.subtransient_time_constants(np.zeros(self.mp.n))

    def network(self, config: StageConfig = StageConfig()) -> ReducedNetwork:
        """Reduced network of a stage (the STAGES_KEPT most recently used are kept)."""
        return self._stage_cache.get(config, lambda: self._reduce(config))

    def _reduce(self, config: StageConfig) -> ReducedNetwork:
        case = self.case
        bus = case.buses.matrix().copy()
        line = case.branches.matrix().copy()
        y_shunt = self.y_load.copy()
        for b, y in config.faults:
            kept = 0.0 if self.conventions == "pstess" or y == -1j * FAULT_B else 1.0
            bus[b, 7], bus[b, 8] = kept * bus[b, 7] + y.real, kept * bus[b, 8] + y.imag
        for b, y in config.load_steps:
            y_shunt[b] += y
        on = np.zeros(self.mo.n)
        on[list(config.motors_on)] = 1.0
        np.add.at(y_shunt, self.mo.bus_idx, on * mot.admittance(self.mo))
        # PSTess keeps an opened line's charging; a breaker de-energises it (ieee)
        b_open = 1.0 if self.conventions == "pstess" else 0.0
        for row in config.opened:
            line[row, 3], line[row, 4] = OPEN_X, line[row, 4] * b_open
        new_bus, new_line = [], []
        next_number = bus[:, 0].max() + 10
        for row, far, faulted in config.fault_feeds:
            nl = line[row].copy()
            line[row, 3], line[row, 4] = OPEN_X, line[row, 4] * b_open
            nb = np.zeros(bus.shape[1])
            nb[[0, 1, 9]] = next_number, 1.0, 3
            nb[8] = -FAULT_B if faulted else 0.0
            nl[0], nl[1] = next_number, far
            nl[3] = case.branches.x[row] if faulted else OPEN_X
            nl[4] *= 1.0 if faulted else b_open
            new_bus.append(nb)
            new_line.append(nl)
            next_number += 10
        if new_bus:
            bus = np.vstack([bus, new_bus])
            line = np.vstack([line, new_line])
            y_shunt = np.concatenate([y_shunt, np.zeros(len(new_bus))])
        stage = case.replace(
            buses=BusTable.from_matrix(bus), branches=BranchTable.from_matrix(line)
        )
        online = np.ones(self.mp.n, bool)
        online[list(config.tripped_machines)] = False
        converters_on = np.ones(self.cp.n)
        converters_on[list(config.tripped_converters)] = 0.0
        label = bus_islands(_check_machines(stage))
        dead = _islanded(label, self.mp.bus_idx[online], case.n_bus)
        if dead.size:  # PSS/E: the island is de-energised, its load and shunts shed
            self._check_sheddable(dead)
            bus[dead, 7], bus[dead, 8] = 0.0, -FAULT_B  # grounded as by a bolted fault:
            y_shunt[dead] = 0.0  # the island's Y is regular and its voltages 0
            stage = stage.replace(buses=BusTable.from_matrix(bus))
        net = reduce_network(
            stage,
            y_shunt,
            self.mp.y_internal,
            self.mp.bus_idx,
            online,
            self.nc_idx,
            case.n_bus,
            base=self._pre_event_factor(config),
        )
        targets = np.column_stack([self.eqp0, np.ones(self.mp.n)])
        for m, dV, df in config.playback:
            targets[m] += (dV, df)
        steps = np.zeros(self.ep.n + self.gp.n)
        for m, dv in config.vref_steps:
            steps[np.flatnonzero(self.ep.mac == m)] += dv
        for m, dp in config.pref_steps:
            steps[self.ep.n + np.flatnonzero(self.gp.mac == m)] += dp
        shed = case.buses.pload[dead] + 1j * case.buses.qload[dead]
        islanded = tuple((int(case.buses.number[b]), complex(shed[k])) for k, b in enumerate(dead))
        return replace(
            net,
            switched_on=np.concatenate([on, converters_on]),
            targets=targets,
            steps=steps,
            islanded=islanded,
            bus_island=label[: case.n_bus].astype(np.int64),
            machine_island=np.where(online, label[self.mp.bus_idx], -1).astype(np.int64),
            faulted=bool(config.faults) or any(f for _, _, f in config.fault_feeds),
        )

    def _pre_event_factor(self, config: StageConfig):
        """The pre-event network's sparse reduction (`ReducedNetwork.factor`) for a stage
        of a network reduced sparse (`solution.DENSE_MAX`), which is then updated from
        it (`stabctl.network.lowrank`); None for the pre-event stage itself and for
        networks reduced dense (their stages stay bit for bit PSTess's reduction)."""
        if config == StageConfig() or self.mp.n + self.case.n_bus <= solution.DENSE_MAX:
            return None
        return self.network().factor

    def _check_sheddable(self, dead: np.ndarray) -> None:
        """Refuse to de-energise an island holding a device whose model needs a live
        network (a converter, an induction motor, a fixed injection): InputError naming
        the buses and devices."""
        held = {
            "converter": np.concatenate([self.cp.bus_idx, self.cp.bus1_idx, self.cp.bus2_idx]),
            "induction motor": self.mo.bus_idx,
            "static var compensator": self.sv.bus_idx,
            "fixed injection": self.case.bus_indices(self.case.injections.bus)
            if len(self.case.injections)
            else np.zeros(0, int),
        }
        hit = [
            f"{what} at bus {int(self.case.buses.number[b])}"
            for what, buses in held.items()
            for b in sorted(set(np.asarray(buses, int).tolist()) & set(dead.tolist()))
        ]
        if hit:
            numbers = [int(b) for b in self.case.buses.number[dead]]
            raise InputError(
                f"the disturbance islands bus(es) {numbers} from every generator; stabctl "
                f"sheds an island's load and shunts but not a {', '.join(hit)}"
            )

    # -- initialisation ---------------------------------------------------------------
    def _initialise(self):
        mp, ep, op, L = self.mp, self.ep, self.op, self.layout
        xm, self.vex0, self.pmech0 = mac.initialise(mp, op.V, op.S_gen)
        self.eqp0 = xm[2].copy()
        x = np.zeros(L.size)
        L.view(x, "mac")[:] = xm
        eterm0 = np.abs(op.V[mp.bus_idx])
        S0 = op.S_gen[mp.bus_idx]
        S0 = S0.real * mp.pfrac + 1j * S0.imag * mp.qfrac
        em = ep.mac
        VB0 = exc.initial_source_voltage(ep, mp, op.V[mp.bus_idx], S0, self.vex0)
        V0 = op.V[mp.bus_idx]
        I0 = np.conj(S0 / V0) * mp.mac_pot  # machine base
        vc0 = np.abs(V0[em] + (ep.Rcomp + 1j * ep.Xcomp) * I0[em])
        xe, self.Vref, self.ep = exc.initialise(ep, self.vex0[em], eterm0[em], VB0, vc0)
        ep = self.ep
        tau = ep.inner_loop_time_constants(VB0, self.vex0[em])
        #: each exciter's inner-loop time constant at the operating point (n_exc,), s (inf
        #: without one; `stabctl.dynamics.subinterval`)
        self.inner_loops = tau
        k = int(np.argmin(tau)) if tau.size else 0
        #: the fastest loop the data's time constants do not show: (s, where)
        self.fastest_loop = (
            (float(tau[k]), f"exc_con row {k + 1}: {ep.inner_loop(k)}")
            if tau.size and np.isfinite(tau[k])
            else (np.inf, "")
        )
        L.view(x, "exc")[:] = xe
        L.view(x, "pss")[:] = pss_.initialise(
            self.pp,
            *pss_.pss_inputs(self.pp, xm[1], self.pmech0),
            self.pmech0[self.pp.mac],
        )
        lp = np.where(self.gp.mac2 >= 0, self.pmech0[np.maximum(self.gp.mac2, 0)], 0.0)
        xg, self.Pref = gov.initialise(self.gp, self.pmech0[self.gp.mac], lp)
        L.view(x, "tg")[:] = xg
        L.view(x, "ibr")[:] = conv.initialise(self.cp, op.V)
        L.view(x, "swsh")[0] = sws.initial_levels(self.case.switched_shunts)
        L.view(x, "svc")[:] = svc.initialise(self.sv)
        L.view(x, "shaft")[:] = shaft.initialise(
            self.tp, xm[0, self.tp.mac], self.pmech0[self.tp.mac]
        )
        self.x0 = x
        self.V_nc0 = op.V[self.nc_idx].astype(complex)
        self.pss_of_exc = np.full(ep.n, -1)
        self.case.check_stabilisers()  # each PSS's machine has its exciter
        for k, m in enumerate(self.pp.mac):
            self.pss_of_exc[np.nonzero(ep.mac == m)[0]] = k
        self.params = KernelParams(
            MP=mp.packed(self.eqp0),
            basrad=mp.basrad,
            EP=ep.packed(self.Vref),
            SP=self.pp.packed(),
            GP=self.gp.packed(self.Pref),
            IP=self.cp.packed(),
            TP=self.tp.packed(),
            MO=self.mo.packed(),
            SWP=self._shunts_packed(),
            SWY=self._shunt_levels(),
            SVP=self.sv.packed(),
            pss_of_exc=self.pss_of_exc,
            exc_rows=L.exc_rows,
            pss_rows=L.pss_rows,
            tg_rows=L.tg_rows,
            mac_bus=mp.bus_idx.astype(np.int64),
            vex0=self.vex0,
            pmech0=self.pmech0,
            loads=kept_loads(self.nc),
            ieee=self.conventions == "ieee",
            reach=0.0,
            n_mac=L.n_mac,
            n_exc=L.n_exc,
            n_pss=L.n_pss,
            n_tg=L.n_tg,
            n_ibr=L.n_ibr,
            n_shaft=L.n_shaft,
            n_motor=L.n_motor,
            n_swsh=L.n_swsh,
            n_svc=L.n_svc,
            n_bus=self.case.n_bus,
            exc_hmax=np.full(L.n_exc, np.inf),
        )

    def _shunts_packed(self) -> np.ndarray:
        """The switched shunts' packed columns (`stabctl.models.shunts.PACKED`)."""
        t = self.case.switched_shunts
        top = [sws.levels(t, k).size - 1 for k in range(len(t))]
        cols = (
            np.searchsorted(self.nc_idx, self.sw_bus),
            t.vref - t.dv,
            t.vref + t.dv,
            t.dt,
            top,
            sws.initial_levels(t),
        )
        return np.column_stack(cols).astype(float).reshape(len(t), len(shunt.PACKED))

    def _shunt_levels(self) -> np.ndarray:
        """The switched shunts' levels g + j b, complex (n_swsh, most levels), padded."""
        t = self.case.switched_shunts
        ys = [sws.levels(t, k) for k in range(len(t))]
        out = np.zeros((len(t), max((y.size for y in ys), default=1)), complex)
        for k, y in enumerate(ys):
            out[k, : y.size] = y
        return out

    @functools.cached_property
    def island(self) -> np.ndarray:
        """Each machine's island in the case's network, (n_mac,) int
        (`stabctl.network.topology.machine_islands`)."""
        return machine_islands(self.case)

    @functools.cached_property
    def coi_inertia(self) -> np.ndarray:
        """The COI weights of the machines, (n_mac,) (`stabctl.dynamics.coi.coi_inertia`:
        H * MVA, or 1 / 0 in an island with infinite buses), each machine's island's."""
        return coi_inertia(self.mp.H, self.case.machines.mva, self.island)

    @functools.cached_property
    def initial_residual(self) -> tuple[float, str]:
        """Largest |derivative| at t = 0 and the state it belongs to (the initialisation
        check; evaluated on first use, the model's first compiled evaluation), leaving out
        the storage's state of charge, which integrates the device's power and so moves at
        any operating point but a zero output (`converters.ENERGY_SLOTS`).

        Raises
        ------
        SimulationError
            The non-conforming load iteration did not converge at the initial point.
        """
        return self._initial_check[:2]

    @functools.cached_property
    def initial_clamps(self) -> tuple[str, ...]:
        """The limited states the first evaluation clamped (PST clamps a state outside its
        limits in place): each as "state = value at the start, clamped to limit", e.g. a
        simple exciter's E_fd above its EMAX; empty when every state starts within its
        limits.  A start outside a limit is not an equilibrium (`check_equilibrium` names
        these)."""
        return self._initial_check[2]

    @functools.cached_property
    def _initial_check(self) -> tuple[float, str, tuple[str, ...]]:
        x = self.x0.copy()
        dx, _ = self.evaluate(x, self.network(StageConfig()), self.V_nc0)
        dx = np.abs(dx)
        self.layout.view(dx, "ibr")[conv.ENERGY_SLOTS, :] = 0.0  # move at any operating point
        k = int(np.argmax(dx))
        clamps = tuple(
            f"{self.state_name(q)} = {self.x0[q]:.6g}, clamped to {x[q]:.6g}"
            for q in np.flatnonzero(x != self.x0)
        )
        return float(dx[k]), self.state_name(k), clamps

    def check_equilibrium(self, off_equilibrium: str = "refuse") -> None:
        """Refuse (or warn about) an initial point that is not an equilibrium: a largest
        |derivative| at t = 0 (`initial_residual`) above :data:`EQUILIBRIUM_TOL`.

        Every model's initialisation solves its own equations at the power flow, so a
        residual there means two definitions of one quantity disagree (IEEE 39's power-input
        IEEEST fed the terminal power at initialisation and the air-gap power after: 0.015
        on ``pss.leadlag1.G6``, a 6e-5 pu speed drift in a 10 s flat run); the built-in
        cases start within 2e-12 (Kundur 2.7e-13 on ``exc.Efd.G3``, miniWECC 1.9e-12 on
        ``exc.VR.G18``), the PSS/E and ANDES cases read as ANDES solves them within 3e-11.
        A model reproduced as PST has it may start off equilibrium as PST does (PST's
        ``exc_st3`` estimates the field current fed to K_C differently from its
        initialisation: WECC-179 read with ``conventions="pst"``, 0.040 on ``exc.VR.G1``;
        the "psse" and "andes" readings of an ESST3A feed it the machine's own).

        Parameters
        ----------
        off_equilibrium : {"refuse", "warn"}, optional
            Raise (the default) or warn (:class:`UserWarning`) and go on.

        Raises
        ------
        CaseError
            ``off_equilibrium="refuse"`` and the residual is above the tolerance: the
            value and the state (e.g. ``pss.leadlag1.G6``).
        InputError
            ``off_equilibrium`` is neither "refuse" nor "warn".
        """
        if off_equilibrium not in ("refuse", "warn"):
            raise InputError(f"off_equilibrium must be 'refuse' or 'warn', got {off_equilibrium!r}")
        residual, state = self.initial_residual
        if residual <= EQUILIBRIUM_TOL:
            return
        clamps = self.initial_clamps
        why = (
            f"limited state(s) start outside their limits: {'; '.join(clamps[:3])}"
            + (f" and {len(clamps) - 3} more" if len(clamps) > 3 else "")
            + " (the data's limit cannot hold the power flow's operating point)"
            if clamps
            else "a model's initialisation disagrees with its dynamics"
        )
        text = (
            f"case '{self.case.name}': the initial point is not an equilibrium: "
            f"|d{state}/dt| = {residual:.3g} at t = 0 (tolerance {EQUILIBRIUM_TOL:g}); {why}"
        )
        if off_equilibrium == "warn":
            warnings.warn(text, UserWarning, stacklevel=3)
            return
        pst_st3 = (self.ep.kind == exc.ST3) & ~self.ep.ifd_machine
        hint = (
            "; an ESST3A of PSS/E data read with the 'pst' conventions (PST's exc_st3, its "
            "own estimate of the field current) starts off equilibrium with K_C != 0: "
            "import the data with "
            + advice("load_psse(..., conventions='psse')", "import-psse --dyr-conventions psse")
            + " (the default), which reads PSS/E's ESST3A"
            if state.startswith("exc.") and np.any(pst_st3)
            else ""
        )
        anyway = advice(" (Simulator(off_equilibrium='warn') runs it anyway)")
        raise CaseError(f"{text}{hint}{anyway}")

    def state_name(self, k: int) -> str:
        """Name of flat state index k, e.g. 'mac.omega.G3' or 'exc.VTR.G1'."""
        owners = {
            "mac": np.arange(self.mp.n),
            "exc": self.ep.mac,
            "pss": self.pp.mac,
            "tg": self.gp.mac,
            "ibr": np.arange(self.cp.n),
            "shaft": self.tp.mac,
            "motor": np.arange(self.mo.n),
            "swsh": np.arange(len(self.case.switched_shunts)),
            "svc": np.arange(self.sv.n),
        }
        names = {
            "mac": lambda i: mac.STATE_NAMES,
            "pss": lambda i: pss_.STATE_NAMES[int(self.pp.kind[i])],
            "exc": lambda i: exc.STATE_NAMES[int(self.ep.kind[i])],
            "tg": lambda i: gov.STATE_NAMES[int(self.gp.kind[i])],
            "ibr": lambda i: conv.STATE_NAMES[int(self.cp.type[i])],
            "shaft": lambda i: shaft.STATE_NAMES,
            "motor": lambda i: mot.STATE_NAMES,
            "swsh": lambda i: shunt.SLOTS,
            "svc": lambda i: svc.STATE_NAMES,
        }
        for block, (sl, (_rows, n)) in self.layout.blocks.items():
            if sl.start <= k < sl.stop:
                r, i = divmod(k - sl.start, n)
                own = names[block](i)
                state = own[r] if r < len(own) else f"unused{r}"
                if block == "ibr":
                    return f"ibr.{state}.C{int(self.case.converters.number[i])}"
                if block == "motor":
                    return f"motor.{state}.M{int(self.case.motors.number[i])}"
                if block == "swsh":
                    return f"swsh.{state}.S{int(self.case.switched_shunts.number[i])}"
                if block == "svc":
                    return f"svc.{state}.V{int(self.case.svcs.number[i])}"
                number = int(self.case.machines.number[owners[block][i]])
                return f"{block}.{state}.G{number}"
        raise IndexError(f"state index {k} out of range")

    # -- one evaluation -----------------------------------------------------------------
    def evaluate(self, x, net: ReducedNetwork, V_nc_guess, S_extra=None, want_vbus=True):
        """All derivatives at state x with network stage `net` (PST flag 1 + 2).

        Args:
            x: flat state vector (modified in place where PST clamps limited states).
            net: reduced network of the stage; V_nc_guess: kept-bus voltages to start the
                load iteration from; S_extra: extra complex power drawn at the kept buses
                (storage devices), shape (n_nc,), or None; want_vbus: also compute every
                bus voltage (else V_bus is not written).
        Returns:
            (dx flat array, Outputs).
        Raises:
            SimulationError: the non-conforming load iteration did not converge.
        """
        ko = kernel_outputs(self.mp.n, self.case.n_bus, self.cp.n, self.ep.n)
        S = np.zeros(self.nc_idx.size, complex) if S_extra is None else np.asarray(S_extra, complex)
        kept = KeptBuses(
            V=np.array(V_nc_guess, complex), held=np.zeros(S.size, np.bool_), S_extra=S
        )
        dx = np.zeros_like(x)  # slots no kernel writes (e.g. a short PSS in long slots) stay 0
        if evaluate_kernel(x, self.params, kernel_network(net), kept, want_vbus, dx, ko) < 0:
            raise SimulationError("non-conforming load iteration did not converge")
        return dx, Outputs(
            pelect=ko.pelect,
            qelect=ko.qelect,
            eterm=ko.eterm,
            V_bus=ko.V_bus,
            V_nc=kept.V,
            efd=ko.efd,
            pmech=ko.pmech,
            cur=ko.cur,
            S_ibr=ko.S_ibr,
        )


def active_states(model: DynamicModel) -> np.ndarray:
    """Boolean mask (n_x,) of the state slots that are states of the model.

    Unused slots (derivative identically 0, never read as a state): machines mac_tra
    psikd/psikq, mac_em all but delta/omega, an infinite bus's (H = 0) delta/omega too;
    exciters V_TR without T_R, V_As without T_B, the smpexc Efd without T_A; the third PSS
    lead-lag without T_4 (PSTess's lbnd = 1e-3 s); slots a type does not use
    (`ExciterParams.has_state`, `GovernorParams.has_state`).
    """
    L, mp, ep, pp = model.layout, model.mp, model.ep, model.pp
    act = np.zeros(L.size, bool)
    m = L.view(act, "mac")
    m[[0, 1]] = mp.H > 0  # an infinite bus (H = 0) holds its angle and speed
    m[[2, 4]] = mp.kind != mac.EM
    m[[3, 5]] = mp.kind == mac.SUB
    L.view(act, "exc")[:] = ep.has_state()
    L.view(act, "pss")[:] = pp.has_state()
    L.view(act, "tg")[:] = model.gp.has_state()
    L.view(act, "ibr")[:] = model.cp.has_state()
    L.view(act, "shaft")[:] = True
    L.view(act, "motor")[:] = model.case.motors.in_service == 1  # off: standing still
    L.view(act, "swsh")[:] = False  # a switched shunt's level and delay: discrete memory
    L.view(act, "svc")[:] = model.sv.has_state()
    return act


class KernelParams(NamedTuple):
    """Packed parameters of every model for the compiled kernels (see each model's
    `packed`; IP the converters', TP the shafts', MO the motors', SWP and SWY the switched
    shunts' columns and levels, SVP the static var compensators'), the kept buses' load
    array loads (9, n_nc) complex pu (`stabctl.network.solution.kept_loads`, copied by
    each evaluation) and the numbers of
    machines, exciters, PSSs, governors, converters, shafts, motors, switched shunts and
    compensators (the state layout, `Layout`)."""

    MP: np.ndarray
    basrad: float
    EP: np.ndarray
    SP: np.ndarray
    GP: np.ndarray
    IP: np.ndarray
    TP: np.ndarray
    MO: np.ndarray
    SWP: np.ndarray
    SWY: np.ndarray
    SVP: np.ndarray
    pss_of_exc: np.ndarray
    exc_rows: int
    pss_rows: int
    tg_rows: int
    mac_bus: np.ndarray
    vex0: np.ndarray
    pmech0: np.ndarray
    loads: np.ndarray
    ieee: bool
    #: limiter reach (s): the run's step in a simulation, 0 elsewhere
    #: (`stabctl.models.blocks.nonwindup`)
    reach: float
    n_mac: int
    n_exc: int
    n_pss: int
    n_tg: int
    n_ibr: int
    n_shaft: int
    n_motor: int
    n_swsh: int
    n_svc: int
    #: buses of the case (R's rows when a run computes every bus voltage)
    n_bus: int
    #: per exciter (n_exc,), the longest step (s) of the sub-intervals it is integrated in
    #: within a step of the run (`stabctl.dynamics.subinterval`), inf: none (the whole
    #: model's step); finite only in a run that sub-steps a fast exciter loop
    exc_hmax: np.ndarray


class KernelNetwork(NamedTuple):
    """The matrices of a reduced network stage for the kernels (`ReducedNetwork`; in
    `stabctl.dynamics.integrator.integrate` each is stacked by stage on a first axis): Y11
    (n_mac, n_mac), Y12 (n_mac, n_nc), Y21 (n_nc, n_mac), Y22 and Z22 = inv(Y22) (n_nc, n_nc), R
    (n_bus, n_mac + n_nc), R_mac (n_mac, n_mac + n_nc) its machine buses' rows (R (0, n_mac +
    n_nc) in a run that records no bus voltage), Z_mac (n_mac,) the machines' internal
    impedances (0: tripped); complex pu on the system base; targets (n_mac,
    2) the playback sources' targets (`ReducedNetwork.targets`); switched_on (n_motor +
    n_ibr,) float, 1.0 for each motor, then each converter, in service in the stage
    (`ReducedNetwork.switched_on`); steps (n_exc +
    n_tg,) float, the exciters' VREF and governors' PREF changes in the stage
    (`ReducedNetwork.steps`)."""

    Y11: np.ndarray
    Y12: np.ndarray
    Y21: np.ndarray
    Y22: np.ndarray
    Z22: np.ndarray
    R: np.ndarray
    R_mac: np.ndarray
    Z_mac: np.ndarray
    switched_on: np.ndarray
    targets: np.ndarray
    steps: np.ndarray


def kernel_network(net: ReducedNetwork) -> KernelNetwork:
    """The kernel matrices of one reduced network stage.

    Parameters
    ----------
    net : ReducedNetwork
        A stage from `DynamicModel.network`.

    Returns
    -------
    KernelNetwork
        The same arrays (no copy).
    """
    return KernelNetwork(*(np.ascontiguousarray(getattr(net, f)) for f in KernelNetwork._fields))


def stacked_networks(nets, rows=None) -> KernelNetwork:
    """The stages' matrices stacked on a first axis (stage index), C-contiguous.

    Parameters
    ----------
    nets : sequence of ReducedNetwork, length n_stage
        Stages of equal dimensions.
    rows : ndarray of int or None, optional
        R's rows to stack: None (default) every bus's; else those (0-based bus indices,
        possibly none) for a run that records only their voltages (`evaluate_kernel` then
        reads R_mac for the machines; ACTIVSg2000's R is 10.7 MB a stage).

    Returns
    -------
    KernelNetwork
        Each field of shape (n_stage, ...) of the single-stage shape (R: (n_stage,
        len(rows), n_mac + n_nc) with rows).
    """

    def stacked(f):
        if f == "R" and rows is not None:
            return np.ascontiguousarray(np.stack([n.R[rows] for n in nets]))
        return np.ascontiguousarray(np.stack([getattr(n, f) for n in nets]))

    return KernelNetwork(*(stacked(f) for f in KernelNetwork._fields))


class KeptBuses(NamedTuple):
    """State of the kept (non-conforming load and device) buses through an evaluation,
    each (n_nc,): V the complex voltages (pu; the guess in, the solution out), held the
    loads held at their impedance model (`stabctl.network.solution.solve_nc`; updated in
    place), S_extra the complex power the devices draw there (pu, + absorbs)."""

    V: np.ndarray
    held: np.ndarray
    S_extra: np.ndarray


class KernelOutputs(NamedTuple):
    """Algebraic outputs written by `evaluate_kernel`: per machine cur (complex, system
    base), pelect, qelect (system base), eterm, efd, pmech (machine base), all (n_mac,);
    V_bus (n_bus,) complex pu; per converter S_ibr (n_ibr,) the injected P + j Q (pu,
    system base)."""

    cur: np.ndarray
    pelect: np.ndarray
    qelect: np.ndarray
    eterm: np.ndarray
    efd: np.ndarray
    pmech: np.ndarray
    V_bus: np.ndarray
    S_ibr: np.ndarray
    #: (n_exc, N_FROZEN) the inputs of each exciter integrated in sub-intervals
    #: (`stabctl.models.exciters.frozen_inputs`; rows of the others not written)
    exc_in: np.ndarray


@njit(cache=True)
def kernel_outputs(nm, nb, ni, ne):
    """Output buffers for `evaluate_kernel`: (n_mac,) each, V_bus (nb,) and S_ibr (ni,)
    zeros, exc_in (ne, N_FROZEN).

    Parameters
    ----------
    nm : int
        Number of machines.
    nb : int
        Number of buses.
    ni : int
        Number of converters.
    ne : int
        Number of exciters.

    Returns
    -------
    KernelOutputs
    """
    return KernelOutputs(
        np.empty(nm, np.complex128),
        np.empty(nm),
        np.empty(nm),
        np.empty(nm),
        np.empty(nm),
        np.empty(nm),
        np.zeros(nb, np.complex128),
        np.zeros(ni, np.complex128),
        np.zeros((ne, exc.N_FROZEN)),
    )


#: the ``want_vbus`` flags of `evaluate_kernel` for compiled callers, as numpy booleans: a
#: Python True/False passed from compiled code is typed as a literal, and numba would
#: compile `evaluate_kernel` (and its callers) once per value
BUS_VOLTAGES, NO_BUS_VOLTAGES = np.bool_(True), np.bool_(False)


#: the converters' voltage-dependent currents (REGCA1): the network solution is repeated
#: until no drawn current differs from the affine model it was solved with by more than
#: this (pu), at most CURRENT_ITERATIONS times
CURRENT_TOL = 1e-11
CURRENT_ITERATIONS = 50
#: voltage step (pu) of the drawn currents' slope in |V| (one-sided difference; their
#: limits are piecewise linear in |V|, so it is exact away from a breakpoint)
SLOPE_DV = 1e-6


class KeptDevices(NamedTuple):
    """The devices drawing current at the kept buses, for the network solution: the
    converters' packed parameters IP (n_ibr, ...) and states xi (`conv.N_STATES`,
    n_ibr), the motors' MO and states xmo, on (n_motor + n_ibr,) 1.0 for each motor, then
    each converter, in service,
    the switched shunts' SWP, levels SWY and memory xsw, the compensators' SVP and states
    xsv (`KernelParams`, `Layout`).  The kernels below take these ten arrays, not the
    whole `KernelParams`: a compiled call costs about 10 ns for every array it is passed
    (measured)."""

    IP: np.ndarray
    xi: np.ndarray
    MO: np.ndarray
    xmo: np.ndarray
    on: np.ndarray
    SWP: np.ndarray
    SWY: np.ndarray
    xsw: np.ndarray
    SVP: np.ndarray
    xsv: np.ndarray


@kernel
def _summed_currents(dev, V_nc, dv):
    """`conv.drawn_current` of every converter at its bus voltage magnitude + dv (pu), and
    the current of every motor on beside its admittance (`mot.drawn_current`), summed per
    kept bus, and the switched shunts' and compensators' admittance beyond the network's
    (`shunt.extra_admittance`, `svc.extra_admittance`) as a drawn current: (I_rel,
    I_fix), each (n_nc,) complex; dev the `KeptDevices`."""
    rel = np.zeros(V_nc.size, np.complex128)
    fix = np.zeros(V_nc.size, np.complex128)
    n_motor = dev.xmo.shape[1]
    for k in range(dev.xi.shape[1]):
        if dev.on[n_motor + k] == 0.0:  # tripped (`ConverterTrip`)
            continue
        pos = int(dev.IP[k, conv.C.POS])
        a, b = conv.drawn_current(dev.IP, dev.xi, k, abs(V_nc[pos]) + dv)
        rel[pos] += a
        fix[pos] += b
    for k in range(dev.xmo.shape[1]):
        if dev.on[k] != 0.0:
            fix[int(dev.MO[k, mot.Q.POS])] += mot.drawn_current(dev.MO, dev.xmo, k)
    for k in range(dev.xsw.shape[1]):
        pos = int(dev.SWP[k, shunt.S.POS])
        y = shunt.extra_admittance(dev.SWP, dev.SWY, dev.xsw, k)
        rel[pos] += np.conj(y) * (abs(V_nc[pos]) + dv)
    for k in range(dev.xsv.shape[1]):
        pos = int(dev.SVP[k, svc.V.POS])
        y = svc.extra_admittance(dev.SVP, dev.xsv, k)
        rel[pos] += np.conj(y) * (abs(V_nc[pos]) + dv)
    return rel, fix


@kernel
def _drawn_currents(dev, V_nc, loads, tol):
    """The devices' currents drawn at the kept buses at voltages V_nc (`_summed_currents`,
    dev the `KeptDevices`) against the affine model of loads (rows `LOAD`: I_dev + G_dev |V|,
    I_fix + G_fix |V|, each (n_nc,) complex): if the model misses one by more than tol,
    the model is made the tangent at V_nc (in place: the slope from the currents at |V| +
    SLOPE_DV, evaluated only then).  Returns the largest miss."""
    rel, fix = _summed_currents(dev, V_nc, 0.0)
    moved = 0.0
    for i in range(V_nc.size):
        m = abs(V_nc[i])
        moved = max(
            moved,
            abs(rel[i] - loads[LOAD.I_dev, i] - loads[LOAD.G_dev, i] * m),
            abs(fix[i] - loads[LOAD.I_fix, i] - loads[LOAD.G_fix, i] * m),
        )
    if moved > tol:
        rel2, fix2 = _summed_currents(dev, V_nc, SLOPE_DV)
        for i in range(V_nc.size):
            m = abs(V_nc[i])
            g_rel, g_fix = (rel2[i] - rel[i]) / SLOPE_DV, (fix2[i] - fix[i]) / SLOPE_DV
            loads[LOAD.G_dev, i], loads[LOAD.G_fix, i] = g_rel, g_fix
            loads[LOAD.I_dev, i] = rel[i] - g_rel * m
            loads[LOAD.I_fix, i] = fix[i] - g_fix * m
    return moved


@kernel
def _converter_fixed_point(dev, Y21, Y22, Z22, psi, V_nc, loads, held, it, V_start):
    """The network solution with the converters' drawn currents when one depends on its
    bus voltage (REGCA1's LVG and HVG, `conv.drawn_current`): solved with their tangent
    at the starting voltages (`_drawn_currents`; it the iteration count of that solution,
    -1 if it failed), which is exact while no |V| crosses a breakpoint of their
    piecewise-linear limits; otherwise the tangent is taken again at the solved voltages
    and the network solved again, until the currents agree within CURRENT_TOL.  If that
    fails, `_converter_newton` from the starting voltages V_start.  Returns the total
    load-iteration count, -1 without convergence."""
    for _ in range(CURRENT_ITERATIONS):
        if it < 0:
            break
        if _drawn_currents(dev, V_nc, loads, CURRENT_TOL) <= CURRENT_TOL:
            return it
        more = solve_nc(Y21, Y22, Z22, psi, V_nc, loads, held)
        it = it + more if more >= 0 else -1
    assign(V_nc, V_start)
    return _converter_newton(dev, Y21, Y22, psi, V_nc, loads, held)


@kernel
def _converter_newton(dev, Y21, Y22, psi, V_nc, loads, held):
    """Newton's method on the kept-bus equations with the converters' currents as they
    are, piecewise linear in |V|: their tangent taken again at every iterate, as ANDES's
    Newton iteration reads its Piecewise blocks (LVG, HVG) at every iterate.  Needed where
    the tangent at the starting voltages has no solution at all: a fault beside a REGCA1
    (kundur_reg, bus 8: the pre-fault LVG of 1 keeps the 7 pu current source at full
    active current, and behind the bus's 0.045 pu Thevenin reactance, 0.22 pu of
    Thevenin voltage, no bus voltage carries it, while at the voltage that solves the
    equations LVG is 0).  Returns the iteration count, -1 without convergence within
    NEWTON_MAX_ITER."""
    for it in range(NEWTON_MAX_ITER):
        _drawn_currents(dev, V_nc, loads, -1.0)
        if newton_step(Y21, Y22, psi, V_nc, loads, held):
            return it
    return -1


@kernel
def _switched(SWP, xsw, V_nc, dxsw):
    """The switched shunts' discrete control (`shunt.switch`; SWP their packed columns,
    xsw their memory) at the solved kept-bus voltages V_nc: True if one stepped."""
    moved = False
    for k in range(xsw.shape[1]):
        level = xsw[0, k]
        shunt.switch(SWP, xsw, k, abs(V_nc[int(SWP[k, shunt.S.POS])]), dxsw)
        moved = moved or xsw[0, k] != level
    return moved


@njit(cache=True)
def evaluate_kernel(x, p, net, kept, want_vbus, dx, out):
    """One evaluation in PSTess's order (docs/pst_models.md 7.2): machine flag 1, network,
    PSS / exciter / governor flag 1, then flag 2 of machines, PSS, exciters, governors.

    Parameters
    ----------
    x : ndarray, shape (n_state,)
        Flat state (`Layout`); limited states are clamped in place as PST does.
    p : KernelParams
        Model parameters and sizes.
    net : KernelNetwork
        Matrices of the network stage.
    kept : KeptBuses
        Kept-bus voltages (guess in, solution out) and held loads, updated in place; the
        device powers drawn there.
    want_vbus : bool
        Compute the bus voltages of net.R's rows into out.V_bus (every bus, or those a
        run records); else none (net.R may be empty).  The machines' terminal voltages
        come from V_bus when it holds every bus, else from net.R_mac.
    dx : ndarray, shape (n_state,)
        Written with the derivatives (slots no model uses are left as they are).
    out : KernelOutputs
        Written with the algebraic outputs.

    Returns
    -------
    int
        The load-iteration count, -1 without convergence.
    """
    nm, ne = p.n_mac, p.n_exc
    scratch = _Scratch(
        np.empty(nm, np.complex128),
        np.empty(nm, np.complex128),
        np.empty(nm, np.complex128),
        np.empty(nm, np.complex128),
        np.empty(p.n_pss),
        p.vex0.copy(),
        np.empty(nm),
        np.empty(nm),
        np.empty(ne),
        np.empty(ne),
        np.empty(ne),
        np.zeros(ne),
        np.empty(ne),
    )
    return _evaluate_into(x, p, net, kept, want_vbus, dx, out, scratch)


class _Scratch(NamedTuple):
    """The per-evaluation arrays of `_evaluate_into`: per machine its internal voltage psi,
    rotation exp(j delta), current from the kept buses, terminal voltage (complex), field
    voltage handed to it, field current and air-gap saturation; per PSS its output; per
    exciter its algebraic field voltage, field current, source term, PSS input and its
    machine's terminal voltage magnitude as PST exc_st3 recomputes it (`exc.stator`)."""

    psi: np.ndarray
    rot: np.ndarray
    I_kept: np.ndarray
    V_mac: np.ndarray
    pss_out: np.ndarray
    vex: np.ndarray
    ifd_mac: np.ndarray
    gap: np.ndarray
    efd_alg: np.ndarray
    ifd: np.ndarray
    vb: np.ndarray
    pss_exc: np.ndarray
    et: np.ndarray


@kernel
def _evaluate_into(x, p, net, kept, want_vbus, dx, out, scratch):
    """`evaluate_kernel` with its per-evaluation arrays given (`_Scratch`).  Every array
    is borrowed (`stabctl._jit.borrow`; the caller holds them for the whole call), so that
    the per-element calls below count no references: half of a run's time before."""
    x, p, net, kept, dx, out, scratch = borrowed((x, p, net, kept, dx, out, scratch))
    psi, rot, I_kept, V_mac, pss_out, vex, ifd_mac, gap, efd_alg, ifd, vb, pss_exc, et = scratch
    nm, ne, nps, ng, ni = p.n_mac, p.n_exc, p.n_pss, p.n_tg, p.n_ibr
    Y11, Y12, Y21, Y22, Z22, R, R_mac, Z_mac, on, targets, steps = net
    EP = _stepped(p.EP, steps[:ne], _VREF)
    GP = _stepped(p.GP, steps[ne:], _PREF)
    V_nc, held, S_extra = kept
    cur, pelect, qelect, eterm, efd, pmech, V_bus, S_ibr, exc_in = out
    o, re, rp, rg = 6 * nm, p.exc_rows, p.pss_rows, p.tg_rows
    xm, dxm = x[:o].reshape(6, nm), dx[:o].reshape(6, nm)
    xe, dxe = x[o : o + re * ne].reshape(re, ne), dx[o : o + re * ne].reshape(re, ne)
    o += re * ne
    xp, dxp = x[o : o + rp * nps].reshape(rp, nps), dx[o : o + rp * nps].reshape(rp, nps)
    o += rp * nps
    xg, dxg = x[o : o + rg * ng].reshape(rg, ng), dx[o : o + rg * ng].reshape(rg, ng)
    o += rg * ng
    ri = conv.N_STATES
    xi, dxi = x[o : o + ri * ni].reshape(ri, ni), dx[o : o + ri * ni].reshape(ri, ni)
    o += ri * ni
    rt, nt = shaft.N_STATES, p.n_shaft
    xt, dxt = x[o : o + rt * nt].reshape(rt, nt), dx[o : o + rt * nt].reshape(rt, nt)
    o += rt * nt
    rm, nmo = mot.N_STATES, p.n_motor
    xmo, dxmo = x[o : o + rm * nmo].reshape(rm, nmo), dx[o : o + rm * nmo].reshape(rm, nmo)
    o += rm * nmo
    rs, nsw = shunt.N_STATES, p.n_swsh
    xsw, dxsw = x[o : o + rs * nsw].reshape(rs, nsw), dx[o : o + rs * nsw].reshape(rs, nsw)
    o += rs * nsw
    rv, nv = svc.N_STATES, p.n_svc
    xsv, dxsv = x[o : o + rv * nv].reshape(rv, nv), dx[o : o + rv * nv].reshape(rv, nv)
    dev = KeptDevices(p.IP, xi, p.MO, xmo, on, p.SWP, p.SWY, xsw, p.SVP, xsv)
    mac.internal_voltage(p.MP, xm, psi, rot)
    v_dep = False
    for k in range(ni):
        conv.clamp_states(p.IP, xi, k, p.reach)
        v_dep = v_dep or conv.voltage_dependent(p.IP, k)
    loads = p.loads.copy()
    assign(loads[LOAD.S_extra], S_extra)
    if ni or nmo or nsw or nv:  # the converters' tangent at the starting voltages, the
        # motors', the switched shunts' and the compensators' currents
        _drawn_currents(dev, V_nc, loads, -1.0)
    V_start = V_nc.copy() if v_dep else V_nc
    it = solve_nc(Y21, Y22, Z22, psi, V_nc, loads, held)
    if v_dep:  # currents that depend on the voltage (REGCA1): repeat until they agree
        it = _converter_fixed_point(dev, Y21, Y22, Z22, psi, V_nc, loads, held, it, V_start)
    if it < 0:
        return -1
    if nsw and _switched(p.SWP, xsw, V_nc, dxsw):  # a shunt stepped: the network again
        _drawn_currents(dev, V_nc, loads, -1.0)
        if v_dep:
            assign(V_start, V_nc)
        more = solve_nc(Y21, Y22, Z22, psi, V_nc, loads, held)
        if v_dep:
            more = _converter_fixed_point(dev, Y21, Y22, Z22, psi, V_nc, loads, held, more, V_start)
        if more < 0:
            return -1
        it += more
    matvec(Y11, psi, cur)
    matvec(Y12, V_nc, I_kept)
    for m in range(nm):  # a tripped machine (Z_mac 0, its node grounded) carries none
        cur[m] = cur[m] + I_kept[m] if Z_mac[m] != 0 else 0.0
    z = np.concatenate((psi, V_nc))
    if want_vbus and V_bus.size > 0:  # R: every bus's rows, or those a run records
        matvec(R, z, V_bus)
    if want_vbus and V_bus.size == p.n_bus:
        for m in range(nm):
            V_mac[m] = V_bus[p.mac_bus[m]]
    elif z.size > SMALL_MATVEC:  # behind each machine's impedance: O(n_mac) instead of
        for m in range(nm):  # the product with R_mac (ACTIVSg2000: 27 us an evaluation,
            if Z_mac[m] != 0:  # a fifth of it); equal to it up to round-off
                V_mac[m] = psi[m] - Z_mac[m] * cur[m]
            else:  # a tripped machine: its bus's voltage
                V_mac[m] = dot(R_mac[m], z)
    else:  # row by row, as every bus's product sums it (a loop at this size)
        for m in range(nm):
            V_mac[m] = dot(R_mac[m], z)
    for k in range(nps):
        m = int(p.SP[k, pss_.S.MAC])
        pe = (psi[m] * np.conj(cur[m])).real * p.MP[m, mac.K.POT]
        vt = magnitude(V_mac[m].real, V_mac[m].imag)
        pss_out[k] = pss_.output_and_derivatives(p.SP, xp, k, xm[1, m], pe, vt, dxp)
    mac.field_currents(p.MP, xm, cur, rot, ifd_mac, gap)
    for i in range(ne):
        m = int(EP[i, exc.E.MAC])
        if p.pss_of_exc[i] >= 0:
            pss_exc[i] = pss_out[p.pss_of_exc[i]]
        ifd[i] = exc.field_current(EP, i, ifd_mac)
        stator = exc.stator(p.MP, xm, cur, rot, m, V_mac[m])
        et[i] = stator.et
        vb[i] = exc.source_voltage(EP, i, p.MP, xm, cur, rot, stator, ifd[i])
        efd_alg[i] = exc.field_voltage(EP, xe, i, xm, et[i], pss_exc[i], ifd[i], vb[i], p.ieee)
        vex[m] = efd_alg[i]
    assign(pmech, p.pmech0)
    for k in range(ng):
        m = int(GP[k, gov.G.MAC])
        pmech[m] = gov.pmech(GP, xg, k, xm[1, m])
        if GP[k, gov.G.MAC2] >= 0:  # a cross-compound unit's LP shaft
            pmech[int(GP[k, gov.G.MAC2])] = gov.pmech_lp(GP, xg, k)
    mac.derivatives(
        p.MP,
        p.basrad,
        xm,
        cur,
        rot,
        ifd_mac,
        gap,
        vex,
        _rotor_inputs(p.TP, p.MP, xm, xt, pmech),
        targets,
        dxm,
        pelect,
        qelect,
        eterm,
    )
    for k in range(nt):
        shaft.derivatives(p.TP, p.MP, p.basrad, xt, k, xm, pmech, dxt)
    assign(efd, p.vex0)
    for i in range(ne):
        m = int(EP[i, exc.E.MAC])
        vc = eterm[m]
        if EP[i, exc.E.RCOMP] != 0.0 or EP[i, exc.E.XCOMP] != 0.0:
            pot = p.MP[m, mac.K.POT]
            vc = exc.compensated(EP, i, V_mac[m], cur[m] * pot)
        if p.exc_hmax[i] < np.inf:  # integrated in sub-intervals: its inputs held
            exc.frozen_inputs(EP, i, xm, et[i], pss_exc[i], ifd[i], vb[i], vc, eterm[m], exc_in[i])
        exc.derivatives(
            EP, xe, i, vc, eterm[m], pss_exc[i], efd_alg[i], ifd[i], vb[i], dxe, p.ieee, p.reach
        )
        efd[m] = exc.recorded_efd(EP, xe, i, efd_alg[i])
    for k in range(ng):
        m = int(GP[k, gov.G.MAC])
        gov.derivatives(GP, xg, k, xm[1, m], pelect[m] * p.MP[m, mac.K.POT], dxg)
    for k in range(ni):
        V_k = V_nc[int(p.IP[k, conv.C.POS])]
        S_ibr[k] = conv.derivatives(p.IP, xi, k, V_k, V_nc, p.reach, dxi)
        if on[nmo + k] == 0.0:  # tripped (`ConverterTrip`): no output, states still
            S_ibr[k] = 0.0
            dxi[:, k] = 0.0
    for k in range(nmo):
        mot.derivatives(p.MO, xmo, k, V_nc[int(p.MO[k, mot.Q.POS])], on[k], dxmo)
    for k in range(nv):
        svc.derivatives(p.SVP, xsv, k, abs(V_nc[int(p.SVP[k, svc.V.POS])]), dxsv)
    _freeze_tripped(p, EP, GP, Z_mac, dxm, dxe, dxp, dxg, dxt)
    return it


@kernel
def _freeze_tripped(p, EP, GP, Z_mac, dxm, dxe, dxp, dxg, dxt):
    """Hold the states of each tripped machine (Z_mac 0) and of its controls (exciter,
    PSS, governor, shaft): out of service, as PSS/E's and ANDES's models of a machine whose
    status is off, so that its recorded speed and angle stay where the trip left them and
    no phantom power drives them (its node grounded, the network solution gave it a
    current |psi|, an electrical power |psi|^2: Kundur's G4 tripped at 1 s read 1.15-1.48
    pu and ran away).  An exciter integrated in sub-intervals (`stabctl.dynamics.subinterval`)
    runs on, its output feeding nothing."""
    tripped = False
    for m in range(p.n_mac):
        if Z_mac[m] == 0:
            dxm[:, m] = 0.0
            tripped = True
    if not tripped:  # every evaluation of every run: the controls' loops only after a trip
        return
    for i in range(p.n_exc):
        if Z_mac[int(EP[i, exc.E.MAC])] == 0:
            dxe[:, i] = 0.0
    for k in range(p.n_pss):
        if Z_mac[int(p.SP[k, pss_.S.MAC])] == 0:
            dxp[:, k] = 0.0
    for k in range(p.n_tg):
        if Z_mac[int(GP[k, gov.G.MAC])] == 0:
            dxg[:, k] = 0.0
    for k in range(p.n_shaft):
        if Z_mac[int(p.TP[k, shaft.T.MAC])] == 0:
            dxt[:, k] = 0.0


#: the packed columns the VREF / PREF steps move, as numpy integers (a Python literal
#: passed to a kernel compiles it once per value: tests/test_jit_rules.py)
_VREF, _PREF = np.int64(exc.E.VREF), np.int64(gov.G.PREF)


@kernel
def _stepped(P, d, col):
    """Packed parameters P, or, if one of the changes d (one per row of P, or none) is
    nonzero, a copy with them added to column col: the exciters' VREF or the governors'
    PREF of a stage (`KernelNetwork.steps`; VrefStep / PrefStep events)."""
    for k in range(d.size):
        if d[k] != 0.0:
            Q = P.copy()
            for j in range(d.size):
                Q[j, col] += d[j]
            return Q
    return P


@kernel
def _rotor_inputs(TP, MP, xm, xt, pmech):
    """The mechanical power each machine's swing equation takes: the turbine's P_m, or on
    a machine with a torsional shaft (TP their packed columns, xt their states) the
    shaft's torque on its rotor (`stabctl.models.shafts.rotor_torque`) as the P_m giving
    that torque."""
    if xt.shape[1] == 0:
        return pmech
    pm = pmech.copy()
    for k in range(xt.shape[1]):
        m = int(TP[k, shaft.T.MAC])
        torque = shaft.rotor_torque(TP, xt, k, xm[0, m], xm[1, m])
        pm[m] = torque * (xm[1, m] if mac.divides_pmech_by_speed(MP, m) else 1.0)
    return pm


@functools.cache
def _evaluate_arg_types() -> tuple:
    """The types of every argument of `evaluate_kernel` but p, as `call_evaluate` passes
    them: x, net (2-D matrices), kept, want_vbus, dx, out, every array C-contiguous."""
    from numba import typeof

    z, c = np.zeros(1), np.zeros(1, np.complex128)
    m = np.zeros((1, 1), np.complex128)
    net = KernelNetwork(m, m, m, m, m, m, m, c, np.zeros(1), np.zeros((1, 2)), np.zeros(1))
    return (
        typeof(z),
        typeof(net),
        typeof(KeptBuses(c, np.zeros(1, np.bool_), c)),
        types.boolean,
        typeof(z),
        typeof(KernelOutputs(c, z, z, z, z, z, c, c, np.zeros((1, 1)))),
    )


def evaluate_address(p) -> int:
    """Machine-code address of `evaluate_kernel` compiled for parameters p and the
    argument types of `call_evaluate` (loaded from the cache or compiled here;
    `stabctl._jit.address.address_of`).

    Parameters
    ----------
    p : KernelParams

    Returns
    -------
    int
        The address; valid while this process lives (the dispatcher keeps the code).
    """
    from numba import typeof

    x, *rest = _evaluate_arg_types()
    return address_of(evaluate_kernel, (x, typeof(p), *rest))


def _call_evaluate_types() -> tuple:
    x, *rest = _evaluate_arg_types()
    return (x, None, *rest)


#: ``call_evaluate(address, x, p, net, kept, want_vbus, dx, out)``: `evaluate_kernel`
#: through its machine-code address (`evaluate_address`), inside compiled code; its
#: exceptions propagate.  Calling by address instead of by name keeps the model out of the
#: caller's compiled unit: `stabctl.dynamics.integrator.integrate` compiles without it (in a
#: child process when neither is cached, `stabctl._jit.background.compile_in_background`,
#: while this process compiles the model) and LLVM does not optimise and emit the model a
#: second time.  Every argument but p must have the type `evaluate_address` compiled for
#: (`_evaluate_arg_types`: C-contiguous arrays, a boolean want_vbus; TypingError
#: otherwise), or the call would read its arguments wrongly.
call_evaluate = by_address(
    "call_evaluate", ("x", "p", "net", "kept", "want_vbus", "dx", "out"), _call_evaluate_types
)


def _warn_netted(case: Case, has_mac: np.ndarray, S_free: np.ndarray) -> None:
    """Name the generation the dynamic model nets as negative load: power-flow generation
    (n_bus,) complex, pu, at buses without a machine (has_mac) and not a converter's or a
    compensator's share (S_free).  PSS/E nets such generators only when told (GNET; the
    import's --net-unmodelled); a case file gets the same said aloud."""
    bus = np.nonzero(~has_mac & (np.abs(S_free) > 1e-6))[0]
    if bus.size == 0:
        return
    shown = ", ".join(
        f"bus {int(case.buses.number[b])}: {S_free[b].real:.4g}{S_free[b].imag:+.4g}j"
        for b in bus[:10]
    )
    more = f" and {bus.size - 10} more" if bus.size > 10 else ""
    warnings.warn(
        f"case '{case.name}': generation at {bus.size} bus(es) without a machine is netted "
        f"as negative constant-impedance load in dynamic runs ({shown}{more} pu); give "
        "each a machine (mac_con) to model it",
        UserWarning,
        stacklevel=4,
    )


def _check_machines(stage: Case) -> Case:
    """The stage; InputError for a case without machines."""
    stage.require_machines("a dynamic run or linearisation needs at least one")
    return stage


def _islanded(label: np.ndarray, source_buses: np.ndarray, n_orig: int) -> np.ndarray:
    """Indices (< n_orig) of the buses a stage leaves without a path to any online
    machine (label: the stage's bus islands, `bus_islands`; source_buses: the online
    machines' bus indices)."""
    live = np.isin(label, label[source_buses])
    return np.nonzero(~live[:n_orig])[0]


@dataclass
class Outputs:
    """Algebraic outputs of one evaluation: per machine pelect, qelect (system base), eterm,
    efd, pmech (machine base), cur (complex, system base); V_bus (n_bus,), V_nc; per
    converter S_ibr (n_ibr,) the injected P + j Q (pu, system base)."""

    pelect: np.ndarray
    qelect: np.ndarray
    eterm: np.ndarray
    V_bus: np.ndarray
    V_nc: np.ndarray
    efd: np.ndarray
    pmech: np.ndarray
    cur: np.ndarray
    S_ibr: np.ndarray
