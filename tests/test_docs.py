"""The docs site builds with ``mkdocs build --strict`` and states what the code does."""

from __future__ import annotations

import dataclasses
import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGES = sorted(DOCS.rglob("*.md"))


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The site built from this checkout (its hooks import this checkout's package)."""
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [env.get("PYTHONPATH")])])
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-4000:]
    return out


@pytest.mark.slow
def test_the_metrics_reference_documents_every_public_function_with_its_equations(
    site: Path,
) -> None:
    import pytest_emrd.metrics as metrics

    page = (site / "reference" / "metrics" / "index.html").read_text()
    functions = [n for n in metrics.__all__ if callable(getattr(metrics, n)) and n.islower()]
    missing = [n for n in functions if f'id="pytest_emrd.metrics.{n}"' not in page]
    assert functions and missing == []
    assert page.count('class="arithmatex"') >= 10  # the docstrings' .. math:: blocks
    assert ".. math::" not in page and ":func:`" not in page


@pytest.mark.slow
def test_the_cli_reference_prints_every_emrd_subcommand(site: Path) -> None:
    from pytest_emrd.cli import COMMANDS

    page = (site / "reference" / "cli" / "index.html").read_text()
    assert all(f"emrd {name.replace('_', '-')}" in page for name in COMMANDS)
    assert "usage: emrd report" in page


@pytest.mark.slow
def test_the_performance_page_holds_the_generated_table(site: Path) -> None:
    page = (site / "performance" / "index.html").read_text()
    assert "<!-- performance-table -->" not in page
    assert re.search(r"<th[^>]*>warm</th>", page) and re.search(r"<th[^>]*>cold</th>", page)
    assert "<code>metrics.grid_240_s</code>" in page


@pytest.mark.slow
def test_the_catalogue_page_lists_every_kind_of_object(site: Path) -> None:
    from pytest_emrd.world import KINDS

    page = (site / "reference" / "catalogue" / "index.html").read_text()
    assert "<!-- emrd-catalogue -->" not in page
    rows = re.findall(r"<tr>\s*<td>(\w+)</td>", page)
    assert rows == list(KINDS)
    assert "<td>Office (4)</td>" in page  # the paper office's four desks


def test_every_pytest_option_is_in_the_options_reference() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "--help", "-p", "no:cacheprovider"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    flags = set(re.findall(r"(--emrd-[a-z-]+)", done.stdout))
    reference = (DOCS / "reference" / "cli.md").read_text()
    assert flags and sorted(f for f in flags if f"`{f}" not in reference) == []


def _yaml(value: object) -> str:
    if value is None:
        return "null"
    return str(value).lower() if isinstance(value, bool) else str(value)


def test_the_registry_reference_gives_every_field_and_its_default() -> None:
    from pytest_emrd.agent import ModelConfig

    page = (DOCS / "reference" / "registry.md").read_text()
    for field in dataclasses.fields(ModelConfig):
        if field.name == "name":
            continue  # the entry's key
        if field.default is not dataclasses.MISSING:
            default = f"`{_yaml(field.default)}`"
        elif field.default_factory is not dataclasses.MISSING:
            default = f"`{_yaml(field.default_factory())}`"
        else:
            default = "required"
        assert f"| `{field.name}` | {default}" in page, field.name


def test_the_protocol_page_prints_the_system_prompt_the_code_builds() -> None:
    """The paper's prompt figures are blank, so this copy is the reference others cite."""
    from pytest_emrd.agent import build_system_prompt
    from pytest_emrd.world import paper_office

    text = (DOCS / "reference" / "protocol.md").read_text()
    section = text.split("## The system prompt", 1)[1]
    printed = re.search(r"```text\n(.*?)\n```", section, re.DOTALL)
    assert printed, "the protocol page lost its ```text block"
    code = build_system_prompt(paper_office().inventory(), "default", modality="vision")
    assert printed.group(1) == code


def test_the_protocol_page_states_the_paper_office_as_built() -> None:
    from pytest_emrd.world import paper_office

    office = paper_office()
    text = " ".join((DOCS / "reference" / "protocol.md").read_text().split())
    assert f"{office.width} m × {office.depth} m" in text
    for room in office.rooms:
        size = f"({room.x1 - room.x0:.1f} × {room.z1 - room.z0:.1f} m)"
        assert re.search(rf"{room.name} (top|bottom)-(left|right) {re.escape(size)}", text), room
    assert f"adjacent rooms; {len(office.objects)} objects" in text


def test_the_architecture_page_names_every_package_and_only_those() -> None:
    listed = re.findall(r"^([a-z_]+)/ ", (DOCS / "architecture.md").read_text(), re.MULTILINE)
    beside = re.findall(r"^\| `([a-z_]+)/` \|", (DOCS / "architecture.md").read_text(), re.M)
    packages = {p.parent.name for p in (ROOT / "pytest_emrd").glob("*/__init__.py")}
    repository = {"benchmarks", "cassettes", "docs", "examples", "perf", "pytest_emrd", "tests"}
    assert set(listed) | set(beside) == packages | repository


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(DOCS)))
def test_the_docs_are_no_diary(page: Path) -> None:
    """History belongs to git log: no commit hashes, no load averages, no "previous stop"."""
    text = page.read_text()
    assert not re.search(r"\b(?=[0-9a-f]*\d)(?=[0-9a-f]*[a-f])[0-9a-f]{7,40}\b", text)
    assert not re.search(r"load average|previous (stop|table|release)", text, re.IGNORECASE)


def test_the_interpretation_script_imports_what_it_measures_with() -> None:
    # It reaches into private functions to switch rules off; a rename must fail here, not
    # when someone next regenerates the pages' figures.
    path = ROOT / "docs" / "interpretation" / "measure_effects.py"
    spec = importlib.util.spec_from_file_location("measure_effects", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert callable(module.main) and callable(module.serial_ties)


FACES = sorted(p.parent.name for p in (ROOT / "pytest_emrd").glob("*/__init__.py"))


def _docstring_style() -> str:
    found = re.search(r"^\s+docstring_style: (\w+)$", (ROOT / "mkdocs.yml").read_text(), re.M)
    assert found, "mkdocs.yml names no docstring_style"
    return found.group(1)


@pytest.fixture(scope="module")
def package() -> Any:
    """The package as griffe (mkdocstrings' loader) reads it from this checkout."""
    import griffe

    return griffe.load("pytest_emrd", search_paths=[str(ROOT)], resolve_aliases=False)


@pytest.mark.parametrize("face", FACES)
def test_every_public_function_documents_its_parameters_and_returns(
    face: str, package: Any
) -> None:
    """Habit 13, parsed in the style the site renders (pytest_emrd.metrics first of all):
    every parameter named, and what comes back unless the function returns None."""
    import importlib
    import inspect

    module = importlib.import_module(f"pytest_emrd.{face}")
    style, gaps = _docstring_style(), {}
    for name in module.__all__:
        function = getattr(module, name)
        if not inspect.isfunction(function):
            continue
        path = function.__module__.removeprefix("pytest_emrd.")
        obj = package[f"{path}.{function.__qualname__}"]
        sections = obj.docstring.parse(style) if obj.docstring else []
        named = {p.name for s in sections if s.kind.value == "parameters" for p in s.value}
        missing = [p.name for p in obj.parameters if p.name not in named | {"self", "cls"}]
        returns = obj.returns is not None and str(obj.returns) == "None"
        if not returns and all(s.kind.value != "returns" for s in sections):
            missing.append("(returns)")
        if missing:
            gaps[name] = missing
    assert gaps == {}


def test_every_package_face_declares_all() -> None:
    import importlib

    faces = {n: importlib.import_module(f"pytest_emrd.{n}") for n in FACES}
    assert [n for n, face in faces.items() if not hasattr(face, "__all__")] == []
    assert {n: [a for a in f.__all__ if not hasattr(f, a)] for n, f in faces.items()} == {
        n: [] for n in faces
    }
