"""make_simulator: backends by name, a clear error for unknown ones and missing extras."""

from __future__ import annotations

import pytest

from pytest_emrd.errors import ConfigError, MissingExtraError
from pytest_emrd.world import BACKENDS, BuiltinSimulator, _registry, make_simulator


def test_builtin_is_the_default_and_takes_options() -> None:
    assert isinstance(make_simulator(), BuiltinSimulator)
    assert isinstance(make_simulator("builtin", jpeg_quality=70), BuiltinSimulator)
    assert set(BACKENDS) == {"builtin", "ai2thor"}


def test_unknown_backend_lists_the_known_ones() -> None:
    with pytest.raises(ConfigError, match=r"backend='unity' is not one of 'builtin', 'ai2thor'"):
        make_simulator("unity")


def test_missing_ai2thor_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    def no_ai2thor(name: str):
        raise ModuleNotFoundError("No module named 'ai2thor'", name="ai2thor")

    monkeypatch.setattr(_registry.importlib, "import_module", no_ai2thor)
    with pytest.raises(MissingExtraError, match=r"pip install 'pytest-emrd\[thor\]'"):
        make_simulator("ai2thor")


def test_other_import_errors_are_not_disguised(monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(name: str):
        raise ModuleNotFoundError("No module named 'yaml'", name="yaml")

    monkeypatch.setattr(_registry.importlib, "import_module", broken)
    with pytest.raises(ModuleNotFoundError, match="yaml"):
        make_simulator("ai2thor")
