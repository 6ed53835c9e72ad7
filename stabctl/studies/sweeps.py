"""CCT sweeps with another ESD controller than the paper's (`stabctl sweep-cct` with the
controller options).

:func:`stabctl.stability.cct.cct_jobs` runs every rating with the paper's bang-bang
controller (Table 3). :func:`controlled_cct_jobs` gives the same jobs with another
controller: each job then builds its fleet with that controller, and its key says so
(``/ctrl-db<deadband>-vg<gate>-<coi>-hy<hysteresis>``), so that records of different
controllers never mix in one output file. With the paper's controller the jobs are
exactly :func:`~stabctl.stability.cct.cct_jobs`' (same keys and inputs: earlier records
resume).  With WECC batteries (``esd_model="wecc"``, `stabctl.storage.devices`) the key
ends in ``/wecc``.
"""

from __future__ import annotations

from stabctl.dynamics.options import ModelOptions
from stabctl.stability.cct import (
    SearchOptions,
    cached_simulator,
    cct_jobs,
    searched_job,
)
from stabctl.storage.control import BangBangCOI
from stabctl.storage.devices import model_inputs, uniform_fleet


def controlled_cct_job(inputs: dict) -> dict:
    """Worker entry: :func:`stabctl.stability.cct.cct_job` with the ESD controller of the
    inputs.

    Parameters
    ----------
    inputs : dict
        :func:`~stabctl.stability.cct.cct_job`'s inputs and ``controller``: the
        :class:`~stabctl.storage.devices.BangBangCOI` fields (deadband_hz, v_gate_pu,
        coi, hysteresis_hz), optionally ``esd_model`` ("ideal", the default, or "wecc");
        esd_pct None: no storage (the controller unused).

    Returns
    -------
    dict
        `CCTResult.to_dict()` with the rating, controller and devices' model it answers
        (checked on resume, as `cct_job`'s rating).
    """
    model = ModelOptions.from_inputs(inputs)
    sim = cached_simulator(inputs["case"], model, digest=inputs.get("case_digest"))
    esd_pct = inputs.get("esd_pct")
    fleet = (
        None
        if esd_pct is None
        else uniform_fleet(
            sim.case,
            esd_pct,
            BangBangCOI(**inputs["controller"]),
            model=inputs.get("esd_model", "ideal"),
        )
    )
    own = {"controller": inputs["controller"], "esd_model": inputs.get("esd_model", "ideal")}
    return searched_job(sim, inputs, fleet, **own)


def controlled_cct_jobs(
    case_name: str,
    faults,
    ratings,
    controller: BangBangCOI,
    *,
    search: SearchOptions = SearchOptions(),
    model: ModelOptions = ModelOptions(),
    esd_model: str = "ideal",
) -> list:
    """The jobs of a CCT sweep whose ESDs run ``controller``.

    Parameters
    ----------
    case_name : str
    faults : sequence of LineFault
    ratings : sequence of float or None
        Storage ratings (% of machine MVA; None: no storage).
    controller : BangBangCOI
    search, model : SearchOptions, ModelOptions, optional
        As :func:`stabctl.stability.cct.cct_jobs`.
    esd_model : {"ideal", "wecc"}, optional
        The devices' model (`stabctl.storage.devices.StorageFleet.model`); default
        "ideal".

    Returns
    -------
    list of stabctl.parallel.Job
        :func:`~stabctl.stability.cct.cct_jobs`' jobs for the paper's controller and ideal
        devices (or no storage); else run by :func:`controlled_cct_job`, the controller
        and the model in their inputs and keys.
    """
    from stabctl.parallel import Job

    jobs = cct_jobs(case_name, faults, ratings, search=search, model=model)
    if controller == BangBangCOI() and esd_model == "ideal":
        return jobs
    ctrl = {
        "deadband_hz": controller.deadband_hz,
        "v_gate_pu": controller.v_gate_pu,
        "coi": controller.coi,
        "hysteresis_hz": controller.hysteresis_hz,
    }
    tag = (
        ""
        if controller == BangBangCOI()
        else f"/ctrl-db{controller.deadband_hz:g}-vg{controller.v_gate_pu:g}-{controller.coi}"
        f"-hy{controller.hysteresis_hz:g}"
    ) + ("/wecc" if esd_model == "wecc" else "")
    extra = {"controller": ctrl, **model_inputs(esd_model)}
    return [
        j
        if j.inputs["esd_pct"] is None
        else Job(
            key=j.key + tag,
            func=controlled_cct_job,
            inputs={**j.inputs, **extra},
            check=j.check,
            compared=j.compared,
        )
        for j in jobs
    ]
