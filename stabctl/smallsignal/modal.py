"""Modal analysis of a linearised model (`stabctl.smallsignal.linearise`): eigenvalues,
eigenvectors, participation factors, mode shapes, electromechanical modes and their local /
inter-area classification, residues, controllability and observability.

Conventions (docs/modal.md):
- right eigenvectors phi_i (columns of `right`) have unit 2-norm; left eigenvectors psi_i
  (rows of `left`) are the rows of inv(right), so psi_i phi_j = delta_ij (Kundur, Power
  System Stability and Control, 12.2).  When right is numerically singular (condition
  number above MAX_COND: A defective, a Jordan block such as a chain of integrators held at
  a limit, a wind turbine's pitch PI) they are LAPACK's left eigenvectors, each computed on
  its own and scaled so that psi_i phi_i = 1, so that the defective eigenvalue does not
  spoil the others; the defective one (|psi_i phi_i| below DEFECTIVE_TOL for unit vectors)
  gets psi_i = 0 and the participations |phi_ki|^2;
- participation factors p_ki = |phi_ki psi_ik| / sum_k |phi_ki psi_ik|: each MODE's
  participations (a column) sum to 1 over the states.  (ANDES 2.0's `pfactors` divides by
  the sum over the modes for each state instead, i.e. along the wrong axis.);
- one mode per complex-conjugate pair (imaginary part >= 0); frequency |Im lambda| / 2 pi
  (Hz), damping ratio -Re lambda / |lambda|;
- the angle-reference mode (the common rotation of all rotor angles, A e = 0 analytically
  since no machine is taken as reference) is the mode whose right eigenvector is closest
  in direction to e; it is excluded from damping statistics.  An islanded network has one
  per island (the rotation e_I of island I's angles alone; the modes whose right
  eigenvectors lie nearest the span of the e_I).  A model with an infinite bus (a machine
  of H = 0, whose angle and speed are not states, so the model has fewer speed states
  than omega_G outputs) has none: the infinite bus is the reference.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from stabctl.errors import InputError, WrongTypeError, advice, counted, is_whole_number

F_MIN_HZ, F_MAX_HZ = 0.1, 2.5  # electromechanical band
INTER_AREA_ETA = 0.5  # area-momentum fraction above which a mode is inter-area
# inter-area modes lie below about 1 Hz, local plant modes at 0.8-2 Hz (Kundur, Power System
# Stability and Control, 12.1; Rogers, Power System Oscillations, 1.3): a mode above this
# is local whatever its area momentum (a swing of neighbours across an area boundary)
INTER_AREA_MAX_HZ = 1.0
#: share of an electromechanical mode's kinetic energy that moves the centre of inertia,
#: |sum_k M_k s_k|^2 / (sum_k M_k * sum_k M_k |s_k|^2) (1 when every machine swings alike),
#: above which the mode is "common": the centre of inertia itself swinging (a governor or
#: exciter mode of the system's frequency), where machines swinging against each other move
#: it little (ANDES's IEEE 14 read as PSS/E reads it: 0.18 Hz, 0.994; pjm5bus 0.11 Hz,
#: 1.000).  A swing of some machines against others keeps some momentum where loads make
#: large transfer conductances: pjm5bus's 1.09 Hz mode, three machines against a fourth
#: that barely moves, 0.70 (its momentum fraction |sum M s| / sum M |s| 0.998), and its
#: 1.73 Hz mode, one machine against the others, 0.20 (0.68): ANDES's three swing modes
COMMON_SHARE = 0.9
GAP_RATIO = 1.3  # consecutive EM frequencies this far apart: time-scale gap
SIGNIFICANT = 0.2  # |speed shape| (of the largest) to count in a coherent group
#: how far (degrees) from the largest speed component, or from its opposite, a component
#: may lie and still swing with it, or against it (`ModalAnalysis.groups`); between: in
#: quadrature, on neither side
QUADRATURE_DEG = 60.0
STATE_GROUPS = (
    *("rotor angle/speed", "rotor flux", "exciter", "pss", "governor", "converter"),
    "motor",
    "compensator",
)
#: the STATE_GROUPS index of each block a state's name starts with, up to its first '_'
#: (`state_group`: a machine's angle and speed are its rotor angle/speed, its other states
#: its rotor flux; a torsional shaft's masses are rotor angles and speeds too)
BLOCK_GROUPS = {"mac": 1, "shaft": 0, "exc": 2, "pss": 3, "tg": 4, "ibr": 5, "motor": 6, "svc": 7}
#: |Im lambda| / |lambda| at or below which an eigenvalue is real (`eigen`)
REAL_TOL = 1e-9
#: condition number of the right-eigenvector matrix above which A counts as defective
MAX_COND = 1e10
#: |psi phi| of unit left and right eigenvectors below this (an eigenvalue condition number
#: above 1e4; LAPACK splits a 2-block into two eigenvalues sqrt(eps) apart, |psi phi| ~ 1e-7)
DEFECTIVE_TOL = 1e-4


class AreaCountError(InputError):
    """A number of coherent areas outside [1, the electromechanical modes + 1] or above
    the machines (`coherent_areas`)."""


#: the least-damped modes `ModalAnalysis.table` lists when there is no electromechanical one
LEAST_DAMPED_SHOWN = 5
#: real part above which a mode is unstable (1/s): the angle-reference mode's, left out,
#: is a few 1e-9 (central differences' rounding), an unstable mode's 1e-3 and more
UNSTABLE_REAL_PER_S = 1e-6


@dataclass(frozen=True, eq=False)
class ModalAnalysis:
    """Modes of a linearised model.

    Attributes (n states, m modes = one per conjugate pair, g machines):
        eigenvalues (m,) complex (Im >= 0), ordered by frequency then real part;
        freq_hz, damping (m,); right (n, m) phi_i, left (m, n) psi_i (psi_i phi_i = 1);
        participation (n, m) real, columns sum to 1; states (n,) names; machines (g,)
        numbers; inertia (g,) H*MVA weights; speed_shape (g, m) complex omega components of
        phi_i scaled so the largest is 1 + 0j; reference_modes: indices of the
        angle-reference modes, one per island of machines (none where an infinite bus
        holds the angles; `reference_mode` the first or None); island (g,) island label
        (0..) of each machine; electromechanical: indices of the electromechanical modes;
        areas (g,) area label (0..r-1) of each machine, an area within one island; kind
        (m,) 'angle reference', 'common' (every machine in phase, the centre of inertia
        swinging: its share of the mode's kinetic energy above COMMON_SHARE,
        `coi_energy_share`, without an infinite bus), 'inter-area' (area momentum
        fraction above INTER_AREA_ETA at INTER_AREA_MAX_HZ or below), 'local' or
        'other'; eta (m,) area-momentum fraction (NaN outside the EM modes).
    """

    eigenvalues: np.ndarray
    freq_hz: np.ndarray
    damping: np.ndarray
    right: np.ndarray
    left: np.ndarray
    participation: np.ndarray
    states: np.ndarray
    machines: np.ndarray
    inertia: np.ndarray
    speed_shape: np.ndarray
    reference_modes: tuple[int, ...]
    island: np.ndarray
    electromechanical: np.ndarray
    areas: np.ndarray
    kind: np.ndarray
    eta: np.ndarray

    @property
    def reference_mode(self) -> int | None:
        """The angle-reference mode of a connected network (the first of
        `reference_modes`, one per island), None where an infinite bus holds the angles."""
        return self.reference_modes[0] if self.reference_modes else None

    def reference_values(self) -> str:
        """The angle-reference modes' eigenvalues as text ('-2.50e-07 1/s'; an islanded
        network's one per island, '3.2e-08 and 7.8e-08 1/s, one per island of machines'),
        '' where an infinite bus holds the angles."""
        values = [f"{self.eigenvalues[i].real:.2e}" for i in self.reference_modes]
        if len(values) < 2:
            return f"{values[0]} 1/s" if values else ""
        return f"{', '.join(values[:-1])} and {values[-1]} 1/s, one per island of machines"

    def _mode(self, i) -> int:
        """Mode index i checked: a whole number within the modes (round 45: 999 gave
        numpy's IndexError, -1 the last mode without a word, '1' an IndexError)."""
        n = self.speed_shape.shape[1]
        if not is_whole_number(i) or not 0 <= i < n:
            raise InputError(f"mode index {i!r}: a whole number from 0 to {n - 1} is needed")
        return int(i)

    def groups(self, i: int) -> tuple[list[int], list[int]]:
        """Coherent groups of mode i: machine numbers swinging with the largest speed
        component and those swinging against it (components >= SIGNIFICANT of the largest;
        with it = within QUADRATURE_DEG degrees of it, against it = within QUADRATURE_DEG
        of its opposite), each sorted by decreasing amplitude; the others are in
        quadrature (`quadrature`), on neither side."""
        s = self.speed_shape[:, self._mode(i)]
        big = np.abs(s) >= SIGNIFICANT
        order = np.argsort(-np.abs(s))
        sel = lambda m: [int(self.machines[k]) for k in order if big[k] and m[k]]  # noqa: E731
        angle = np.degrees(np.abs(np.angle(s)))
        return sel(angle <= QUADRATURE_DEG), sel(angle >= 180 - QUADRATURE_DEG)

    def quadrature(self, i: int) -> list[int]:
        """The machines of mode i whose speed component (>= SIGNIFICANT of the largest) is
        more than QUADRATURE_DEG degrees from both the largest component and its opposite:
        in neither coherent group (round 41: Kundur's 1.157 Hz local mode without PSS read
        "G2 G3 vs G1 G4", G3 at 85 degrees and G4 at -96 sorted by the sign of a cosine,
        where the participation says G2 against G1), by decreasing amplitude."""
        s = self.speed_shape[:, self._mode(i)]
        angle = np.degrees(np.abs(np.angle(s)))
        off = (np.abs(s) >= SIGNIFICANT) & (angle > QUADRATURE_DEG) & (angle < 180 - QUADRATURE_DEG)
        return [int(self.machines[k]) for k in np.argsort(-np.abs(s)) if off[k]]

    def area_groups(self, i: int) -> tuple[list[int], list[int]]:
        """Areas (1-based labels) whose momentum, M s summed over the area, is at least
        SIGNIFICANT of the largest area's in mode i: those in phase (within 90 degrees)
        with the machine of the largest speed component, as `groups` orients its sides,
        and those against it, each sorted by decreasing momentum.  An inter-area mode
        moves the areas' centres of inertia, so a side may hold an area of many machines
        each too small to count in `groups`."""
        m = self.inertia * self.speed_shape[:, self._mode(i)]  # largest component 1 + 0j
        p = np.bincount(self.areas, m.real) + 1j * np.bincount(self.areas, m.imag)
        big = np.abs(p) >= SIGNIFICANT * np.abs(p).max()
        order = np.argsort(-np.abs(p))
        sel = lambda m: [int(a) + 1 for a in order if big[a] and m[a]]  # noqa: E731
        return sel(p.real >= 0), sel(p.real < 0)

    def area_sides(self, i: int) -> str:
        """The areas inter-area mode i swings against each other: '1, 3 vs 2' (1-based
        area labels, `area_groups`); '-' for any other mode."""
        if self.kind[self._mode(i)] != "inter-area":
            return "-"
        a1, a2 = (", ".join(str(a) for a in sorted(side)) for side in self.area_groups(i))
        return f"{a1} vs {a2 or '-'}"

    def table(self, name: Callable[[int], str] | None = None) -> str:
        """The electromechanical modes as text, one line each by frequency: index,
        frequency (Hz), damping ratio (column ``zeta``, -Re lambda / |lambda|), kind, the
        machines swinging against each other (at most six a side) and an inter-area mode's
        areas (what ``stabctl eig`` prints).

        Parameters
        ----------
        name : callable or None, optional
            How a machine is named from its number (``stabctl eig``: the case's
            `stabctl.case.Case.machine_name`, ``"G2 (bus 3)"``); default ``"G2"``.

        Returns
        -------
        str
            A header line and one line per electromechanical mode (an unstable one
            marked UNSTABLE), the rotor modes above the band, then whether the model is
            small-signal stable, naming every unstable mode the lines above leave out;
            without any electromechanical mode, a line saying so (and why, for a model
            without machines) and the least-damped LEAST_DAMPED_SHOWN modes with their
            dominant state.
        """
        named = name or (lambda k: f"G{k}")
        em = self.electromechanical
        if not em.size:
            return self._no_electromechanical()
        lines = [f"{'mode':>5} {'f Hz':>7} {'zeta':>8}  {'kind':<10} machines"]
        for i in em[np.argsort(self.freq_hz[em])]:
            g1, g2 = self.groups(i)
            against = " ".join(named(k) for k in g2[:6]) or (
                "none (all in phase: the system's frequency)"
                if self.kind[i] == "common"
                else "none"
                if self.quadrature(i)
                else "others (each < 0.2)"
            )
            areas = f"  [areas {self.area_sides(i)}]" if self.kind[i] == "inter-area" else ""
            quad = " ".join(named(k) for k in self.quadrature(i)[:6])
            quad = f" (in quadrature: {quad})" if quad else ""
            lines.append(
                f"{i:5d} {self.freq_hz[i]:7.3f} {self.damping[i]:8.4f}  {self.kind[i]:<10} "
                f"{' '.join(named(k) for k in g1[:6])} vs {against}{quad}{areas}"
                + ("  UNSTABLE" if self.damping[i] < 0 else "")
            )
        shown = np.concatenate([em, self.rotor_modes_above_band()])
        return "\n".join(
            lines + self._outside_band_lines(named) + self._unstable_lines(shown, named)
        )

    def unstable_modes(self) -> np.ndarray:
        """Indices of the modes with a positive real part (above `UNSTABLE_REAL_PER_S`),
        one per conjugate pair, the angle-reference mode left out: every one, whatever its
        band (an exciter's 3.7 Hz modes at +5.2 1/s were in no table, round 41)."""
        lam = self.eigenvalues
        bad = (lam.real > UNSTABLE_REAL_PER_S) & (lam.imag >= 0)
        bad[list(self.reference_modes)] = False
        return np.nonzero(bad)[0]

    def _unstable_lines(self, shown: np.ndarray, named) -> list[str]:
        """`table`'s lines on the unstable modes: those it does not list named with their
        dominant states (and machines), or a line that every mode is stable."""
        bad = self.unstable_modes()
        if not bad.size:
            return ["small-signal stable: every mode's real part is negative"]
        lines = [
            f"SMALL-SIGNAL UNSTABLE: {counted(bad.size, 'mode')} with a positive real part"
            + (" (marked above)" if np.isin(bad, shown).all() else "")
        ]
        for i in bad[~np.isin(bad, shown)]:
            who = " ".join(named(k) for k in self.dominant_machines(int(i)))
            top = ", ".join(n for n, _ in self.dominant_states(int(i), 2))
            lines.append(
                f"{i:5d} {self.freq_hz[i]:7.3f} {self.damping[i]:8.4f}  real part "
                f"{self.eigenvalues[i].real:+.3g} 1/s; states {top}" + (f"; {who}" if who else "")
            )
        return lines

    def rotor_modes_above_band(self) -> np.ndarray:
        """Indices of the oscillatory modes above the electromechanical band (F_MAX_HZ)
        whose largest participating state group is still the rotor angle and speed: a
        machine's own swing moved out of the band (a tiny H: IEEE 14's G5 at H = 0.05 s
        swings at 13.3 Hz), which the electromechanical modes leave out.  (Below F_MIN_HZ
        such modes are the governors' frequency modes: miniWECC's 0.032 Hz.)"""
        groups = np.array([state_group(n) for n in self.states])
        shares = np.stack([self.participation[groups == g].sum(axis=0) for g in STATE_GROUPS])
        rotor = shares[0] >= shares.max(axis=0)
        return np.nonzero((self.freq_hz > F_MAX_HZ) & rotor & (self.eigenvalues.imag > 0))[0]

    def _outside_band_lines(self, named) -> list[str]:
        """`table`'s lines naming the rotor modes above the band, if any."""
        idx = self.rotor_modes_above_band()
        if not idx.size:
            return []
        lines = [
            f"rotor modes above {F_MAX_HZ:g} Hz (not electromechanical above; a machine's "
            "own swing):"
        ]
        for i in idx[np.argsort(self.damping[idx], kind="stable")]:
            who = " ".join(named(k) for k in self.dominant_machines(int(i)))
            lines.append(f"{i:5d} {self.freq_hz[i]:7.3f} {self.damping[i]:8.4f}  {'':<10} {who}")
        return lines

    def _no_electromechanical(self) -> str:
        why = (
            ": the model has no machine with a rotor (converters against infinite buses)"
            if not self.machines.size
            else ""
        )
        lines = [
            f"no electromechanical mode ({F_MIN_HZ:g}-{F_MAX_HZ:g} Hz, dominated by rotor "
            f"angle and speed states){why}; the least-damped of its {self.eigenvalues.size} "
            "modes (--json lists them all):",
            f"{'mode':>5} {'f Hz':>7} {'zeta':>8}  dominant state",
        ]
        for i in np.argsort(self.damping, kind="stable")[:LEAST_DAMPED_SHOWN]:
            top = self.dominant_states(i, 1)[0][0]
            lines.append(f"{i:5d} {self.freq_hz[i]:7.3f} {self.damping[i]:8.4f}  {top}")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.table()

    def machine_participation(self, i: int) -> np.ndarray:
        """Participation of each machine in mode i, (g,): the sum over all states of the
        machine and of its controls (exciter, PSS, governor, shaft; names ending
        ``_G<k>``); the states of converters, motors, switched shunts and compensators
        belong to no machine (their share: `group_shares`)."""
        owner = np.array([_machine_of(n) for n in self.states])
        return np.array([self.participation[owner == k, i].sum() for k in self.machines])

    def group_shares(self, i: int) -> dict[str, float]:
        """Participation of mode i summed per state group (STATE_GROUPS)."""
        g = np.array([state_group(n) for n in self.states])
        return {name: float(self.participation[g == name, i].sum()) for name in STATE_GROUPS}

    def dominant_states(self, i: int, n: int = 3) -> list[tuple[str, float]]:
        """The n states with the largest participation in mode i."""
        k = np.argsort(-self.participation[:, i])[:n]
        return [(str(self.states[j]), float(self.participation[j, i])) for j in k]

    def dominant_machines(self, i: int, frac: float = 0.5, n: int = 5) -> list[int]:
        """Machines whose participation in mode i is at least frac of the largest (at most n)."""
        p = self.machine_participation(i)
        k = [j for j in np.argsort(-p)[:n] if p[j] >= frac * p.max()]
        return [int(self.machines[j]) for j in k]

    def damping_statistics(self) -> dict:
        """Least damping ratio and its mode, over all modes but the angle reference, over
        the electromechanical modes and over the rotor modes above their band
        (`rotor_modes_above_band`; keys ``all``, ``electromechanical``,
        ``rotor_above_band``, each only when it has a mode)."""
        rest = np.setdiff1d(np.arange(self.eigenvalues.size), self.reference_modes)
        out = {}
        for key, idx in (
            ("all", rest),
            ("electromechanical", self.electromechanical),
            ("rotor_above_band", self.rotor_modes_above_band()),
        ):
            if idx.size:
                j = int(idx[np.argmin(self.damping[idx])])
                out[key] = {
                    "mode": j,
                    "damping_ratio": float(self.damping[j]),
                    "freq_hz": float(self.freq_hz[j]),
                }
        return out

    def mode_record(self, i: int) -> dict:
        """Everything about mode i, JSON-ready."""
        lam = self.eigenvalues[i]
        rec = {
            "mode": i,
            "real_per_s": float(lam.real),
            "imag_rad_per_s": float(lam.imag),
            "freq_hz": float(self.freq_hz[i]),
            "damping_ratio": float(self.damping[i]),
            "stable": bool(lam.real <= UNSTABLE_REAL_PER_S or i in self.reference_modes),
            "kind": str(self.kind[i]),
            "dominant_states": [
                {"state": s, "participation": p} for s, p in self.dominant_states(i)
            ],
        }
        if i in self.electromechanical:
            g1, g2 = self.groups(i)
            a1, a2 = self.area_groups(i)
            rec.update(
                dominant_machines=self.dominant_machines(i),
                group=g1,
                against=g2,
                quadrature=self.quadrature(i),
                areas=a1,
                areas_against=a2,
                area_momentum_fraction=float(self.eta[i]),
                speed_shape={
                    f"G{int(k)}": [float(abs(z)), float(np.degrees(np.angle(z)))]
                    for k, z in zip(self.machines, self.speed_shape[:, i])
                },
            )
        return rec


def state_group(name: str) -> str:
    """STATE_GROUPS entry of a state name such as 'mac_omega_G3', 'exc_VTR_G1',
    'ibr_Ip_C1' (a converter-interfaced device, `stabctl.models.converters`) or
    'shaft_wHP_G1' (a torsional shaft's mass, `stabctl.models.shafts`: rotor angle/speed);
    'svc_thyristor_V1' is a static var compensator's (`stabctl.models.svcs`)."""
    block, _, rest = name.partition("_")
    if block == "mac" and rest.partition("_")[0] in ("delta", "omega"):
        return STATE_GROUPS[0]
    return STATE_GROUPS[BLOCK_GROUPS[block]]


def _continuous_model(sys, caller: str) -> None:
    """`WrongTypeError` naming `caller` unless `sys` is a state-space model with state names,
    `InputError` unless it is a continuous-time one (dt = 0)."""
    if not hasattr(sys, "state_labels"):  # a matrix: no state names to find machines by
        raise WrongTypeError(
            f"{caller}(sys): a control.StateSpace with named states is needed "
            f"(stabctl.linearise's), got {type(sys).__name__}"
        )
    if sys.dt != 0:  # a discrete-time model's eigenvalues are not the s-plane modes
        raise InputError(
            f"{caller}(sys): a continuous-time model (dt = 0, as stabctl.linearise's) is "
            f"needed, got a discrete-time one (dt = {sys.dt})"
        )


def modal_analysis(
    sys, inertia=None, n_areas: int | None = None, areas: dict | None = None
) -> ModalAnalysis:
    """Modes of a linearised model (a control.StateSpace from `stabctl.smallsignal.linearise`).

    Parameters
    ----------
    sys : control.StateSpace
        The model, n states; its state names identify machine angle/speed states
        ('mac_delta_G<k>', 'mac_omega_G<k>').
    inertia : array_like or None, optional
        H*MVA per machine (shape (g,), s*MVA, in the order of the speed states) for the
        coherency weights (default: the weights of the model's 'omega_coi' output, i.e.
        the ones `linearise` used; equal weights where the COI is an infinite bus, whose
        model gives the others no weight).
    n_areas : int or None, optional
        Number of coherent areas (default: from the largest gap between consecutive
        electromechanical frequencies, `coherent_areas`).
    areas : dict or None, optional
        The planner's own areas, machine number -> label (every machine), instead of
        coherency.

    Returns
    -------
    ModalAnalysis
        m modes (one per conjugate pair): eigenvalues, frequencies (Hz), damping ratios,
        right (n, m) and left (m, n) eigenvectors, participation factors (n, m), speed
        mode shapes (g, m), the angle-reference mode, the electromechanical modes
        (0.1-2.5 Hz) and their local / inter-area classification (Kundur, Power System
        Stability and Control, 12.2; conventions in the module docstring).

    Raises
    ------
    InputError
        A discrete-time model (`sys.dt` not 0); states not named as `linearise` names
        them (python-control's x[i] after indexing the model); a model without machine
        speed states given inertia; n_areas out of range; areas missing a machine or
        naming one the model lacks; inertia not one finite weight >= 0 per machine or all
        0.
    WrongTypeError
        `sys` not a state-space model with state names (a bare A matrix); `n_areas` not a
        whole number; `areas` not a dict or a key of it not a machine number (a
        `TypeError` too).

    Examples
    --------
    Kundur's inter-area mode (0.6 Hz: the two areas swinging against each other):

    >>> import stabctl
    >>> sim = stabctl.Simulator(stabctl.load_case("kundur"))
    >>> ma = stabctl.modal_analysis(stabctl.linearise(sim))
    >>> k = ma.electromechanical[0]
    >>> round(float(ma.freq_hz[k]), 3), str(ma.kind[k])
    (0.612, 'inter-area')
    """
    if n_areas is not None and not is_whole_number(n_areas):
        raise WrongTypeError(f"modal_analysis(n_areas): a whole number or None, got {n_areas!r}")
    n_areas = None if n_areas is None else int(n_areas)  # 2.0 failed as a slice index
    if areas is not None and not isinstance(areas, Mapping):
        raise WrongTypeError(
            f"modal_analysis(areas): a dict machine number -> area label or None, got {areas!r}"
        )
    _continuous_model(sys, "modal_analysis")
    states = np.array(sys.state_labels)
    unnamed = [str(n) for n in states if n.partition("_")[0] not in BLOCK_GROUPS]
    if unnamed:
        got = ", ".join(unnamed[:3]) + (", ..." if len(unnamed) > 3 else "")
        raise InputError(
            "modal_analysis(sys): its states are not named as stabctl.linearise names them "
            f"('mac_omega_G1', ...; got {got}), so the machines' states cannot be told; pass "
            "the model linearise returned (indexing it, sys[...], renames its states x[i])"
        )
    speed = np.array([i for i, n in enumerate(states) if n.startswith("mac_omega_G")], int)
    machines = np.array([int(states[i].rsplit("_G", 1)[1]) for i in speed])
    where = {str(n): i for i, n in enumerate(states)}
    angle = np.array([where.get(f"mac_delta_G{k}", -1) for k in machines], int)
    if inertia is not None and speed.size == 0 and np.size(inertia):
        raise InputError(
            f"modal_analysis(sys): no machine speed state (mac_omega_G<n>, as "
            f"stabctl.linearise names them) among its {states.size} states "
            f"({', '.join(states[:3])}, ...), so inertia has no machine to weigh"
        )
    if inertia is None:
        if "omega_coi" not in sys.output_labels:  # a model rebuilt from bare matrices
            raise InputError(
                "modal_analysis(sys): no output 'omega_coi' (stabctl.linearise's) to read "
                "the machines' COI weights from; pass inertia= (H * MVA, one per machine)"
            )
        inertia = sys.C[sys.output_labels.index("omega_coi"), speed]
        if not np.any(inertia):  # the COI is an infinite bus: no weight on the others
            inertia = np.ones(speed.size)
    given = inertia
    try:
        inertia = np.asarray(inertia, float)
    except (TypeError, ValueError):  # (a text gave numpy's bare "could not convert")
        inertia = np.empty(0)  # no numbers: refused below, naming what was given
    if (
        isinstance(given, str)
        or inertia.shape != (speed.size,)
        or not np.all(np.isfinite(inertia) & (inertia >= 0))
        or (speed.size > 0 and not inertia.any())
    ):
        raise InputError(
            f"modal_analysis(inertia): {speed.size} finite weights >= 0, not all 0 (H * MVA, "
            f"one per machine in the order of the speed states) are needed, got {given!r}"
        )
    lam, right, left = eigen(np.asarray(sys.A))
    P = participation_factors(right, left)
    shape = _normalised(right[speed])
    n_mac = sum(1 for n in sys.output_labels if n.startswith("omega_G"))
    infinite_bus = n_mac > speed.size
    island = np.zeros(speed.size, int) if infinite_bus else _islands(sys, states, speed)
    ref = () if infinite_bus else _reference_modes(right, angle, island)
    f, mag = np.abs(lam.imag) / (2 * np.pi), np.abs(lam)
    zeta = np.divide(-lam.real, mag, out=np.ones_like(mag), where=mag > 0)  # lambda = 0: 1
    em = electromechanical_modes(f, P, states)
    if speed.size == 0:  # converters against infinite buses: no rotor, no area
        area_of = _no_machines(n_areas, areas)
    elif areas is None:
        area_of = coherent_areas(shape, f, em, n_areas, island)
    else:
        area_of = _given_areas(areas, machines)
    eta = np.full(lam.size, np.nan)
    eta[em] = area_momentum_fraction(shape[:, em], inertia, area_of)
    kind = np.full(lam.size, "other", dtype=object)
    inter = (eta[em] > INTER_AREA_ETA) & (f[em] <= INTER_AREA_MAX_HZ)
    kind[em] = np.where(inter, "inter-area", "local")
    if ref and speed.size > 1:  # no infinite bus: the COI can swing
        kind[em[coi_energy_share(shape[:, em], inertia) > COMMON_SHARE]] = "common"
    kind[list(ref)] = "angle reference"
    return ModalAnalysis(
        eigenvalues=lam,
        freq_hz=f,
        damping=zeta,
        right=right,
        left=left,
        participation=P,
        states=states,
        machines=machines,
        inertia=np.asarray(inertia, float),
        speed_shape=shape,
        reference_modes=ref,
        island=island,
        electromechanical=em,
        areas=area_of,
        kind=kind.astype(str),
        eta=eta,
    )


def _islands(sys, states: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """Island label (0.., in machine order) of each machine with a speed state, read from
    the model's omega_rel_G<k> outputs (omega_k minus the COI speed of its island,
    `stabctl.smallsignal.linearise`: nonzero on the speeds of its island's machines; a
    machine alone in its island has a zero row).  One island where those outputs are
    missing (a model rebuilt from bare matrices)."""
    outputs = list(sys.output_labels)
    names = ["omega_rel_" + states[i].removeprefix("mac_omega_") for i in speed]
    if not speed.size or any(n not in outputs for n in names):
        return np.zeros(speed.size, int)
    C = np.asarray(sys.C)[[outputs.index(n) for n in names]][:, speed]
    linked = (C != 0) | (C.T != 0) | np.eye(speed.size, dtype=bool)
    return connected_components(csr_matrix(linked), directed=False)[1]


def _reference_modes(right: np.ndarray, angle: np.ndarray, island: np.ndarray) -> tuple:
    """The angle-reference modes, one per island: the modes whose right eigenvectors
    (unit 2-norm) lie nearest the span of the islands' common angle rotations e_I (ones on
    island I's rotor angles; ``angle`` the state index of each machine's, -1 none), ordered
    by mode index."""
    labels = np.unique(island)
    E = np.zeros((right.shape[0], labels.size))
    for j, label in enumerate(labels):
        on = angle[(island == label) & (angle >= 0)]
        E[on, j] = 1.0 / np.sqrt(max(on.size, 1))
    near = np.linalg.norm(E.T @ right, axis=0)
    return tuple(sorted(int(i) for i in np.argsort(-near)[: labels.size]))


def electromechanical_modes(freq_hz: np.ndarray, P: np.ndarray, states) -> np.ndarray:
    """Indices of the modes with F_MIN_HZ <= f <= F_MAX_HZ whose participation summed over
    the rotor angle/speed states is the largest of the STATE_GROUPS."""
    groups = np.array([state_group(n) for n in states])
    shares = np.stack([P[groups == g].sum(axis=0) for g in STATE_GROUPS])  # (groups, modes)
    band = (freq_hz >= F_MIN_HZ) & (freq_hz <= F_MAX_HZ)
    return np.nonzero(band & (shares[0] >= shares.max(axis=0)))[0]


def eigen(A: np.ndarray):
    """Eigenvalues with Im >= 0 (one per conjugate pair), right eigenvectors (unit 2-norm
    columns) and left eigenvectors (rows) scaled so that psi_i phi_i = 1, zero for a
    defective eigenvalue (module docstring).  An eigenvalue with |Im| <= REAL_TOL
    |lambda| is real (Im set to 0, each one kept): a repeated real eigenvalue (Kundur's
    three -100 1/s exciter lags) comes out of LAPACK as a pair +-1e-13 j or as reals
    depending on rounding, which moved every mode number.

    Returns lam (m,), right (n, m), left (m, n), ordered by |Im| then real part.
    """
    lam, V = la.eig(A)
    V /= np.linalg.norm(V, axis=0)
    W = _inverse(V)
    if W is None:  # defective: each left eigenvector on its own (module docstring)
        lam, WL, V = la.eig(A, left=True, right=True)
        V /= np.linalg.norm(V, axis=0)
        WL /= np.linalg.norm(WL, axis=0)
        dot = np.einsum("ij,ij->j", WL.conj(), V)  # psi_i phi_i of unit vectors
        simple = np.abs(dot) > DEFECTIVE_TOL
        W = np.where(simple[:, None], WL.conj().T / np.where(simple, dot, 1.0)[:, None], 0.0)
    real = np.abs(lam.imag) <= REAL_TOL * np.abs(lam)
    lam = np.where(real, lam.real + 0j, lam)
    keep = np.nonzero(real | (lam.imag > 0))[0]
    keep = keep[np.lexsort((lam[keep].real, np.round(np.abs(lam[keep].imag), 9)))]
    return lam[keep], V[:, keep], W[keep]


def _inverse(V: np.ndarray) -> np.ndarray | None:
    """inv(V) from its LU factors, or None when V's 1-norm condition number, estimated
    from the same factors (LAPACK zgecon), exceeds MAX_COND."""
    if V.size == 0:
        return V.T.copy()
    lu = la.lu_factor(V, check_finite=False)
    rcond, _ = la.lapack.zgecon(lu[0], np.abs(V).sum(axis=0).max())
    if rcond * MAX_COND < 1.0:
        return None
    return la.lu_solve(lu, np.eye(V.shape[0], dtype=complex), check_finite=False)


def participation_factors(right: np.ndarray, left: np.ndarray) -> np.ndarray:
    """|phi_ki psi_ik| normalised so that each mode's participations (columns) sum to 1;
    shape (n_states, n_modes); a defective mode (psi_i = 0, `eigen`) |phi_ki|^2."""
    P = np.abs(right * left.T)
    total = P.sum(axis=0)
    return np.where(total > 0, P / np.where(total > 0, total, 1.0), np.abs(right) ** 2)


def _normalised(shape: np.ndarray) -> np.ndarray:
    """Columns scaled so that the largest component is 1 + 0j (zero columns stay zero)."""
    if shape.shape[0] == 0:  # no machine
        return shape
    k = np.argmax(np.abs(shape), axis=0)
    top = shape[k, np.arange(shape.shape[1])]
    return shape / np.where(top == 0, 1.0, top)


def _no_machines(n_areas: int | None, areas: dict | None) -> np.ndarray:
    """The areas of a model without machine speed states (converters against infinite
    buses): none; an area count or a planner's areas given for it are refused."""
    if n_areas is not None or areas:
        raise AreaCountError(
            "the model has no machine with a rotor (no 'mac_omega_G<k>' state: converters "
            "against infinite buses), so no areas: give no number of areas or areas"
        )
    return np.zeros(0, int)


def coherent_areas(
    shape: np.ndarray,
    freq_hz: np.ndarray,
    em: np.ndarray,
    n_areas: int | None = None,
    island: np.ndarray | None = None,
) -> np.ndarray:
    """Coherent areas of the machines by slow coherency (Chow et al., grouping by
    pivoting): the rigid-body directions (one per island: ones on its machines; ``island``
    (g,) labels, default one island) and the speed shapes of the r - s slowest
    electromechanical modes (s islands) span V (g, r); the r machines chosen by QR with
    column pivoting of V^T are the area references; machine k joins the area j maximising
    (V V_ref^-1)_kj (invariant to the basis of the span), so no area spans two islands.

    r (n_areas) defaults to s + the number of slow modes: the electromechanical modes below
    a time-scale gap, taken as the highest ratio of at least GAP_RATIO between consecutive
    sorted frequencies in their lower half (else the largest ratio there).  This is a
    heuristic (Kundur: r = 2, miniWECC: r = 3, docs/modal.md); planners who know their
    areas pass n_areas or `modal_analysis(areas=...)`.  Returns labels (g,), 0 for a
    single area, numbered in the order of each area's first machine (machine order of the
    data: Kundur's area 1 = G1, G2 as in his book).
    Raises AreaCountError (an InputError) for n_areas outside [s, number of EM modes + s]
    or above g.
    """
    g = shape.shape[0]
    island = np.zeros(g, int) if island is None else np.asarray(island)
    rigid = [(island == label).astype(float) for label in np.unique(island)]
    s = len(rigid)
    em = em[np.argsort(freq_hz[em])]
    if n_areas is None:
        n_areas = min(s + _slow_mode_count(freq_hz[em]), g)  # one machine: one area
    if not s <= n_areas <= min(em.size + s, g):
        islands = f" (the machines are in {s} islands)" if s > 1 else ""
        raise AreaCountError(
            f"the number of areas ({advice('n_areas', '--areas')}) must be between {s} and "
            f"{min(em.size + s, g)} (electromechanical modes + {s}, at most the "
            f"machines){islands}, got {n_areas}"
        )
    if n_areas == 1:
        return np.zeros(g, int)
    V = np.column_stack([*rigid, *(shape[:, i].real for i in em[: n_areas - s])])
    _, _, piv = la.qr(V.T, pivoting=True)
    L = V @ np.linalg.inv(V[piv[:n_areas]])
    return _by_first_machine(np.argmax(L, axis=1))


def _by_first_machine(labels: np.ndarray) -> np.ndarray:
    """Area labels renumbered 0..r-1 in the order in which the areas first occur."""
    _, first, inverse = np.unique(labels, return_index=True, return_inverse=True)
    rank = np.empty(first.size, int)
    rank[np.argsort(first)] = np.arange(first.size)
    return rank[inverse]


def _given_areas(areas: Mapping, machines: np.ndarray) -> np.ndarray:
    """Labels 0..r-1 per machine from a machine number -> area mapping (every machine of
    the model and no other)."""
    wrong = [k for k in areas if not is_whole_number(k)]
    if wrong:
        raise WrongTypeError(f"modal_analysis(areas): machine numbers are its keys, got {wrong!r}")
    unknown = sorted(int(k) for k in areas if int(k) not in machines)
    if unknown:
        raise InputError(
            f"modal_analysis(areas): no machine {unknown} in the model (its machines: "
            f"{machines.tolist()})"
        )
    missing = [int(k) for k in machines if int(k) not in areas]
    if missing:
        raise InputError(f"modal_analysis(areas): no area given for machine(s) {missing}")
    _, labels = np.unique([str(areas[int(k)]) for k in machines], return_inverse=True)
    return labels


def _slow_mode_count(f_sorted: np.ndarray) -> int:
    """Number of slow modes: those below the highest frequency gap of at least GAP_RATIO
    among the lower half of the sorted frequencies, else below the largest gap there."""
    if f_sorted.size < 2:
        return f_sorted.size
    ratios = f_sorted[1:] / f_sorted[:-1]
    lower = ratios[: max(1, f_sorted.size // 2)]
    wide = np.nonzero(lower >= GAP_RATIO)[0]
    return int(wide[-1] if wide.size else np.argmax(lower)) + 1


def coi_energy_share(shape: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """The share of each mode's kinetic energy that moves the centre of inertia.

    Parameters
    ----------
    shape : numpy.ndarray
        (g, m) complex speed mode shapes s (one column per mode).
    inertia : numpy.ndarray
        (g,) machine weights M_k (H * MVA).

    Returns
    -------
    numpy.ndarray
        (m,) |sum_k M_k s_k|^2 / (sum_k M_k * sum_k M_k |s_k|^2), in [0, 1]: 1 when every
        machine swings alike (the centre of inertia's own motion), near 0 when they swing
        against each other.  The energy of the speeds splits into the centre of inertia's
        and that of the speeds relative to it (Pai, Energy Function Analysis for Power
        System Stability, 1989, 2.4: the COI reference frame).
    """
    M = np.asarray(inertia, float)
    coi = np.abs(M @ shape) ** 2
    return coi / (M.sum() * (M @ np.abs(shape) ** 2))


def area_momentum_fraction(shape: np.ndarray, inertia: np.ndarray, areas: np.ndarray):
    """eta_i = sum_a |sum_{k in a} M_k s_ki| / sum_k M_k |s_ki| for speed shapes s (g, m).

    Near 1 when whole areas swing against each other (their centres of inertia move:
    inter-area), near 0 when machines swing against others of their own area (local)."""
    M = np.asarray(inertia, float)[:, None]
    num = sum(np.abs((M * shape)[areas == a].sum(axis=0)) for a in np.unique(areas))
    return num / (M * np.abs(shape)).sum(axis=0)


@dataclass(frozen=True, eq=False)
class ModeSensitivity:
    """Residues of every mode between chosen inputs and outputs.

    residues (m, n_out, n_in) complex R_i = (C phi_i)(psi_i B); controllability (m, n_in)
    |psi_i b_j|; observability (m, n_out) |c_k phi_i| (with ||phi_i||_2 = 1,
    psi_i phi_i = 1, so |R_i,kj| = observability * controllability); inputs, outputs: names.
    """

    residues: np.ndarray
    controllability: np.ndarray
    observability: np.ndarray
    inputs: list
    outputs: list


def mode_sensitivity(
    sys, ma: ModalAnalysis, inputs: str = "P_esd_", outputs: str = "omega_rel_"
) -> ModeSensitivity:
    """Residues, controllability and observability of each mode from the inputs whose
    names start with `inputs` to the outputs starting with `outputs` (default: every ESD
    power input to every relative speed).  G(s) = D + sum over all eigenvalues of
    R_i / (s - lambda_i) (the conjugate modes contribute conj(R_i) / (s - conj(lambda_i))).

    Parameters
    ----------
    sys : control.StateSpace
        The model, `stabctl.smallsignal.linearise`'s.
    ma : ModalAnalysis
        Its modes, ``modal_analysis(sys)``.
    inputs, outputs : str, optional
        The start of the names of the inputs and of the outputs.

    Returns
    -------
    ModeSensitivity

    Raises
    ------
    InputError
        A discrete-time model (`sys.dt` not 0); `ma` the modal analysis of another model
        (its states not those of `sys`); no input or output matching.
    WrongTypeError
        `sys` not a state-space model with state names or `ma` not a ModalAnalysis (the
        two swapped; a `TypeError` too).
    """
    _continuous_model(sys, "mode_sensitivity")
    if not isinstance(ma, ModalAnalysis):
        raise WrongTypeError(
            f"mode_sensitivity(ma): a ModalAnalysis (modal_analysis(sys)'s) is needed, got "
            f"{type(ma).__name__}"
        )
    if list(ma.states) != list(sys.state_labels):
        raise InputError(
            f"mode_sensitivity(ma): the modal analysis of another model: its {ma.states.size} "
            f"states are not the {len(sys.state_labels)} of sys, name for name; pass "
            "modal_analysis(sys)"
        )
    ins = [j for j, n in enumerate(sys.input_labels) if n.startswith(inputs)]
    outs = [k for k, n in enumerate(sys.output_labels) if n.startswith(outputs)]
    if not ins or not outs:
        raise InputError(
            f"mode_sensitivity(inputs, outputs): no input starting with {inputs!r} or "
            f"output with {outputs!r}"
        )
    cphi = np.asarray(sys.C)[outs] @ ma.right  # (n_out, m)
    psib = ma.left @ np.asarray(sys.B)[:, ins]  # (m, n_in)
    R = cphi.T[:, :, None] * psib[:, None, :]
    return ModeSensitivity(
        residues=R,
        controllability=np.abs(psib),
        observability=np.abs(cphi.T),
        inputs=[sys.input_labels[j] for j in ins],
        outputs=[sys.output_labels[k] for k in outs],
    )


def match_modes(
    ours: np.ndarray, reference: np.ndarray, f_min: float = F_MIN_HZ, f_max: float = F_MAX_HZ
) -> list[dict]:
    """Pair every reference eigenvalue with Im > 0 and frequency in [f_min, f_max] Hz with
    the nearest of ours (complex arrays, any order, conjugates allowed); each pair as
    {"reference", "ours" (complex), "freq_ref_hz", "freq_err_pct", "damping_ref",
    "damping_err"} (ours minus reference)."""
    ours = np.asarray(ours, complex)
    out = []
    for r in np.asarray(reference, complex):
        f_r = r.imag / (2 * np.pi)
        if not f_min <= f_r <= f_max:
            continue
        o = ours[np.argmin(np.abs(ours - r))]
        f_o = abs(o.imag) / (2 * np.pi)
        z_r = -r.real / abs(r)
        out.append(
            {
                "reference": r,
                "ours": o,
                "freq_ref_hz": f_r,
                "freq_err_pct": 100 * (f_o - f_r) / f_r,
                "damping_ref": z_r,
                "damping_err": -o.real / abs(o) - z_r,
            }
        )
    return out


def _machine_of(name: str) -> int:
    """The machine number of a state named ``..._G<k>``; -1 for any other device's."""
    _, sep, tail = name.rpartition("_G")
    return int(tail) if sep and tail.isdigit() else -1
