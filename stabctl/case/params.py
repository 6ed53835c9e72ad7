"""The registry of the dynamic-data tables: :data:`FAMILIES`, table field of
:class:`~stabctl.case.Case` -> the parameter declarations of its model family.

Each family is declared beside its kernels, one parameter once
(:mod:`stabctl.models.declaration`): ``MACHINE`` in :mod:`stabctl.models.machines`
(``mac_con``), ``EXCITER`` in :mod:`stabctl.models.exciters` (``exc_con``), ``PSS`` in
:mod:`stabctl.models.pss` (``pss_con``), ``GOVERNOR`` in :mod:`stabctl.models.governors`
(``tg_con``), ``CONVERTER`` in :mod:`stabctl.models.converters` (``ibr_con``) ``SHAFT``
in :mod:`stabctl.models.shafts` (``shaft_con``), ``MOTOR`` in :mod:`stabctl.models.motors`
(``mot_con``) and ``SVC`` in :mod:`stabctl.models.svcs` (``svc_con``).  The case
tables (:mod:`stabctl.case.system`), the DYR import and the model reference are built
from this registry.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from stabctl.models.converters import CONVERTER
from stabctl.models.declaration import Family
from stabctl.models.exciters import EXCITER
from stabctl.models.governors import GOVERNOR
from stabctl.models.machines import MACHINE
from stabctl.models.motors import MOTOR
from stabctl.models.pss import PSS
from stabctl.models.shafts import SHAFT
from stabctl.models.svcs import SVC

__all__ = ["FAMILIES"]

#: table field of Case -> family, for the dynamic-data tables
FAMILIES: Mapping[str, Family] = MappingProxyType(
    {
        "machines": MACHINE,
        "exciters": EXCITER,
        "pss": PSS,
        "governors": GOVERNOR,
        "converters": CONVERTER,
        "shafts": SHAFT,
        "motors": MOTOR,
        "svcs": SVC,
    }
)
