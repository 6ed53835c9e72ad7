"""The Examples sections of the public names' docstrings run and print what they show."""

import doctest
import importlib

import pytest

MODULES = [
    "stabctl.io",
    "stabctl.stability.cct",
    "stabctl.smallsignal.modal",
    "stabctl.smallsignal.linearise",
    "stabctl.storage.devices",
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    result = doctest.testmod(module, optionflags=flags, verbose=False)
    assert result.attempted > 0, f"{name}: no example"
    assert result.failed == 0
