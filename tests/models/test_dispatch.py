"""The generated dispatch of the families' compiled kernels (`stabctl.models.dispatch`):
each committed ``_dispatch.py`` is what the generator writes from its registry."""

from __future__ import annotations

import pytest

from stabctl.models import dispatch


@pytest.mark.parametrize("family", dispatch.FAMILIES, ids=lambda f: f.package)
def test_committed_dispatch_is_the_generated_one(family):
    path = dispatch.target(family)
    assert path.read_text("utf-8") == dispatch.render(family), (
        f"{path} is not what the registry {family.package}.MODULES gives: run {dispatch.COMMAND}"
    )


def test_a_type_module_with_other_kernel_arguments_is_named():
    family = dispatch.FAMILIES[0]
    kernel = dispatch.Kernel("pmech", ("P", "x", "k"), "", returns=True)
    module = dispatch.importlib.import_module(family.package).MODULES[0]
    with pytest.raises(ValueError, match=rf"{module.__name__}\.pmech.*take \(P, x, k\)"):
        dispatch._check(module, kernel)
