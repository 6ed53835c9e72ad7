"""The dispatch on the exciter type (exc_con column 1) of the compiled kernels
`field_voltage_at`, `type_derivatives`, `type_recorded_efd`, `source_voltage_of`: generated
by ``python -m stabctl.models.dispatch`` from the registry
(stabctl.models.exciters.MODULES), do not edit."""

from __future__ import annotations

from stabctl._jit.decorators import kernel, njit
from stabctl.models.exciters import (
    ac8b,
    dc,
    esac6a,
    esst1a,
    esst4b,
    exac1,
    exac2,
    exac4,
    expic1,
    exst1,
    ieeet3,
    sexs,
    st3,
    st6b,
    st8c,
)
from stabctl.models.exciters.table import E


@kernel(inline="always")
def field_voltage_at(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """Field voltage of exciter i given its machine's terminal voltage VTR_alg (pu), its
    PSS's output pss_out, the source term VB (`source_voltage`), the field current ifd
    (`field_current`) and the IEEE 421.5 convention ieee: its type module's
    ``field_voltage``."""
    kind = P[i, E.KIND]
    if kind == 3:  # ST3 (exc_st3)
        return st3.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    if kind == 4:  # EXST1
        return exst1.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    if kind == 6:  # ESST1A (IEEE 421.5 ST1A)
        return esst1a.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    if kind == 8:  # EXAC4 (IEEE AC4)
        return exac4.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    if kind == 7 or kind == 9:  # EXAC1 (IEEE AC1); ESAC1A (IEEE 421.5 AC1A)
        return exac1.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    if kind == 10:  # AC8B (IEEE 421.5 AC8B, PID regulator)
        return ac8b.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    if kind == 11:  # IEEET3 (IEEE 1968 type 3, compound source)
        return ieeet3.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    if kind == 12:  # ESST4B (IEEE 421.5 ST4B, PI regulators)
        return esst4b.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    if kind == 13:  # EXAC2 (IEEE AC2)
        return exac2.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    if kind == 14:  # ESAC6A (IEEE 421.5 AC6A)
        return esac6a.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    if kind == 15:  # EXPIC1 (PSS/E proportional-integral exciter)
        return expic1.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    if kind == 16:  # ST6B (IEEE 421.5 ST6B)
        return st6b.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    if kind == 17:  # ST8C (IEEE 421.5 ST8C, field current regulator)
        return st8c.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    if kind == 0:  # simple (smpexc)
        return sexs.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)
    return dc.field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)


@kernel(inline="always")
def type_derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """Derivatives of exciter i past its transducer (`derivatives`) into dx[:, i] for its
    voltage error err: its type module's ``derivatives``."""
    kind = P[i, E.KIND]
    if kind == 3:  # ST3 (exc_st3)
        st3.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    elif kind == 4:  # EXST1
        exst1.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    elif kind == 6:  # ESST1A (IEEE 421.5 ST1A)
        esst1a.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    elif kind == 8:  # EXAC4 (IEEE AC4)
        exac4.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    elif kind == 7 or kind == 9:  # EXAC1 (IEEE AC1); ESAC1A (IEEE 421.5 AC1A)
        exac1.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    elif kind == 10:  # AC8B (IEEE 421.5 AC8B, PID regulator)
        ac8b.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    elif kind == 11:  # IEEET3 (IEEE 1968 type 3, compound source)
        ieeet3.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    elif kind == 12:  # ESST4B (IEEE 421.5 ST4B, PI regulators)
        esst4b.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    elif kind == 13:  # EXAC2 (IEEE AC2)
        exac2.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    elif kind == 14:  # ESAC6A (IEEE 421.5 AC6A)
        esac6a.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    elif kind == 15:  # EXPIC1 (PSS/E proportional-integral exciter)
        expic1.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    elif kind == 16:  # ST6B (IEEE 421.5 ST6B)
        st6b.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    elif kind == 17:  # ST8C (IEEE 421.5 ST8C, field current regulator)
        st8c.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    elif kind == 0:  # simple (smpexc)
        sexs.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)
    else:  # DC1; DC2 (exc_dc12); IEEET2 (DC1 with a two-lag V_R feedback)
        dc.derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)


@kernel(inline="always")
def type_recorded_efd(P, x, i, efd_alg):
    """Efd as PST records exciter i's: its type module's ``recorded_efd`` where it has one,
    else the algebraic field voltage efd_alg."""
    kind = P[i, E.KIND]
    if kind == 11:  # IEEET3 (IEEE 1968 type 3, compound source)
        return ieeet3.recorded_efd(P, x, i, efd_alg)
    if kind == 0:  # simple (smpexc)
        return sexs.recorded_efd(P, x, i, efd_alg)
    if kind == 1 or kind == 2 or kind == 5:
        return dc.recorded_efd(P, x, i, efd_alg)
    return efd_alg  # the other types


@njit
def source_voltage_of(kind, KP, KI, XL, KC, cap, machine, init):
    """The source term V_B of an exciter of type kind from its machine's quantities machine
    (`table.ST3Machine`), its K_P (complex), K_I, X_L, K_C, its cap VBmax and init (PST's
    flag 0): its type module's ``source_voltage`` (the types that declare ``SOURCE``), 1 for
    the others."""
    if kind == 3:  # ST3 (exc_st3)
        return st3.source_voltage(KP, KI, XL, KC, cap, machine, init)
    if kind == 11:  # IEEET3 (IEEE 1968 type 3, compound source)
        return ieeet3.source_voltage(KP, KI, XL, KC, cap, machine, init)
    if kind == 12:  # ESST4B (IEEE 421.5 ST4B, PI regulators)
        return esst4b.source_voltage(KP, KI, XL, KC, cap, machine, init)
    if kind == 15:  # EXPIC1 (PSS/E proportional-integral exciter)
        return expic1.source_voltage(KP, KI, XL, KC, cap, machine, init)
    return 1.0  # the other types
