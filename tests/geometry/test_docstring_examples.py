"""The runnable examples in the geometry docstrings stay true."""

from __future__ import annotations

import doctest
import importlib

import pytest

MODULES = [
    "angles",
    "conic",
    "dial_frame",
    "ellipse_distance",
    "ellipse_fit",
    "ellipse_refine",
    "needle_line",
    "rectify",
    "scale_fit",
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name: str) -> None:
    module = importlib.import_module(f"gauged.geometry.{name}")
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0
    assert result.failed == 0
