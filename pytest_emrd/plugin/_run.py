"""The per-process state of an EMRD run (one :class:`Run` in ``config.stash[RUN]`` per process),
everything heavy built on first use. Paid work is never lost to the disk (docs/security.md):
a live episode needs a writable cassette folder (else nothing is sent to the model), and a
cassette that still cannot be saved goes with the episode's result to ``<run>/unsaved/``."""

from __future__ import annotations

import dataclasses
import json
import shlex
import warnings
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from pytest_emrd._files import check_inside, os_error_line, write_bytes_atomic
from pytest_emrd._scrub import scrub, scrub_bytes, watch_env
from pytest_emrd.errors import ConfigError, EmrdError, check_choice
from pytest_emrd.gate import GateCell, Verdict, evaluate_cell, load_thresholds
from pytest_emrd.plugin._endpoint import EndpointWatch
from pytest_emrd.progress import EpisodeWatch, StatusFile
from pytest_emrd.run import (
    EpisodeSummary,
    ResultsStore,
    RunIdentity,
    RunSettings,
    StoredEpisode,
    cell_specs,
    episode_path,
    episode_specs,
    gate_cells,
    scratch_dir,
    shard,
    start_prefetch,
)
from pytest_emrd.trajectory import CONDITIONS, EpisodeSpec, Trajectory

if TYPE_CHECKING:
    from pytest_emrd.cassette import EpisodeRun, UnsavedCassette
    from pytest_emrd.episode import Executor

RUN = pytest.StashKey["Run"]()
UNSAVED = "unsaved"
"""Folder of a run directory holding live episodes whose cassette could not be written."""


#: Settings the collected grid, the run directory and the store's identity were built from:
#: all but these, which the ``emrd_*`` fixtures may change (:meth:`Run.adopt`).
ADOPTABLE = ("backend_options", "record_mode", "matching", "cassettes", "concurrency", "preflight")


class CassetteNotSavedWarning(UserWarning):
    """A live episode's cassette could not be written; its result was kept elsewhere."""


def failure_line(exc: EmrdError | OSError, what: str = "pytest-emrd") -> str:
    """The one scrubbed line an :class:`EmrdError` or a file system failure ends in."""
    if isinstance(exc, OSError):
        return f"{what}: {scrub(os_error_line(exc, doing='write', option='--emrd-results DIR'))}"
    return f"{what}: {scrub(str(exc))}"


def emrd_params(items: Iterable[pytest.Item]) -> list[EpisodeSpec | GateCell]:
    """The episodes and gates the EMRD tests among ``items`` are parametrised with, in order."""
    params = (getattr(getattr(item, "callspec", None), "params", {}) for item in items)
    return [p[name] for p in params for name in ("emrd_spec", "emrd_gate") if name in p]


@dataclass(eq=False)
class Run:
    """Per-process state of the EMRD run; everything heavy is built on first use."""

    config: pytest.Config
    settings: RunSettings
    run_dir: Path
    session: str

    def __post_init__(self) -> None:
        self._stored: dict[EpisodeSpec, StoredEpisode] = {}
        self._metrics: dict[EpisodeSpec, Any] = {}
        self._prefetch_started, self._prefetcher = False, None
        self._unsaved: dict[EpisodeSpec, str] = {}  # a live episode's cassette not written

    def adopt(self, settings: RunSettings) -> Run:
        """Run the rest of the session with ``settings`` (the ``emrd_*`` fixtures); the fields that
        shaped the collected tests may not change (a :class:`ConfigError` names them)."""
        names = [f.name for f in dataclasses.fields(settings) if f.name not in ADOPTABLE]
        changed = [n for n in names if getattr(settings, n) != getattr(self.settings, n)]
        if changed:
            raise ConfigError(
                f"the emrd_settings fixture changes {', '.join(changed)}, which the collected "
                "tests were built from; set them with --emrd-* options or ini keys instead."
            )
        self.settings = settings
        return self

    def call(self, fn: Any, what: str = "pytest-emrd") -> Any:
        """``fn(self)``, an :class:`EmrdError` turned into one clean failure line (no chain)."""
        try:
            return fn(self)
        except (EmrdError, OSError) as exc:
            message = failure_line(exc, what)
        pytest.fail(message, pytrace=False)

    @cached_property
    def registry(self) -> Any:
        from pytest_emrd.agent import load_registry

        registry = load_registry(self.settings.models_file)
        watch_env(config.api_key_env for config in registry.models.values())
        for name in self.settings.models:
            registry.get(name)
        return registry

    @cached_property
    def protocol(self) -> str:
        from pytest_emrd.protocol import protocol_version  # numpy, via the world

        return protocol_version(self.settings.backend)

    def modality_of(self, model: str) -> str:
        return str(self.registry.get(model).modality)

    @cached_property
    def episode_specs(self) -> list[EpisodeSpec]:
        specs = episode_specs(self.settings, self.modality_of)
        return shard(specs, *self.settings.shard) if self.settings.shard else specs

    @cached_property
    def gate_cells(self) -> list[GateCell]:
        from pytest_emrd.metrics import GATE_METRICS

        if self.settings.shard or self.settings.thresholds is None:
            return []
        thresholds = load_thresholds(
            self.settings.thresholds, registry=self.registry, metrics=GATE_METRICS
        )
        return gate_cells(self.settings, thresholds)

    @cached_property
    def store(self) -> ResultsStore:
        identity = RunIdentity.of(self.settings, self.protocol)
        return ResultsStore(
            self.run_dir, session=self.session, protocol=self.protocol, identity=identity
        )

    @cached_property
    def invocation(self) -> Any:
        """What printed ``pytest`` commands carry: this run's test paths, registry, options."""
        from pytest_emrd.cassette import Invocation

        options = tuple(
            f"{key}={value if isinstance(value, str) else json.dumps(value)}"
            for key, value in self.settings.backend_options
        )
        pyargs = ("--pyargs",) if self.config.option.pyargs else ()  # pytest_emrd.benchmarks
        return Invocation(
            paths=(*pyargs, *self.config.args) or ("benchmarks",),
            models_file=self.settings.models_file,
            cassettes=self.settings.cassettes,
            backend_options=options,
        )

    def missing_summary(self, items: list[pytest.Item]) -> str | None:
        """In record mode ``none``: one message for the episodes the selected items need but
        neither store nor cassette holds, or ``None``."""
        if not self.settings.replays_only:
            return None
        needed = dict.fromkeys(self.specs_of(emrd_params(items)))
        unstored = [spec for spec in needed if not episode_path(self.run_dir, spec).is_file()]
        if not unstored:  # a resumed run: the cassette stage is not even imported
            return None
        from pytest_emrd.cassette import missing_summary

        return missing_summary(
            unstored,
            total=len(needed),
            root=self.settings.cassettes,
            invocation=self.invocation,
            modality_of=self.modality_of,
            episodes=self.settings.episodes,
        )

    @cached_property
    def executor(self) -> Executor:
        """Runs this process's episodes (:class:`pytest_emrd.episode.Executor`)."""
        from pytest_emrd.episode import Executor

        settings = self.settings
        return Executor(
            self.registry,
            backend_options=settings.backend_kwargs,
            cassettes=settings.cassettes,
            protocol=self.protocol,
            record_mode=settings.record_mode,
            matching=settings.matching,
            invocation=self.invocation,
            modality_of=self.modality_of,
            keep_unsaved=True,
        )

    @property
    def session_folder(self) -> Path:
        """This session's folder of the run's scratch space (the live line's status files)."""
        return scratch_dir(self.run_dir) / self.session

    @cached_property
    def endpoints(self) -> EndpointWatch:
        """Consecutive unreachable episodes per model: a dead endpoint stops its model."""
        return EndpointWatch(self.run_dir, self.session, self.config.invocation_params.args)

    @cached_property
    def status_file(self) -> StatusFile:
        return StatusFile(self.session_folder)

    def compute(self, spec: EpisodeSpec) -> EpisodeRun:
        """Run ``spec`` through the executor, watched (an unwritable cassette: see the module
        docstring)."""
        check_inside(self.run_dir, episode_path(self.run_dir, spec), what="episode file")
        tape = self.executor.tape(spec)
        check_inside(self.settings.cassettes, tape.path, what="cassette")
        stopped = self.endpoints.stop_reason(spec.model)
        if stopped is not None:  # a dead endpoint: the model's other episodes skip with its reason
            pytest.skip(stopped)
        with EpisodeWatch(spec, live=tape.live, status=self.status_file) as watch:
            done = self.executor.run(tape, on_step=watch.on_step)
            watch.finish(done.trajectory)
        done = dataclasses.replace(done, retries=watch.retries)
        if done.unsaved is not None:
            self.keep_unsaved(spec, done.unsaved, done.trajectory, retries=done.retries)
        endpoint = self.registry.get(spec.model).base_url or "the built-in reference server"
        self.endpoints.record(spec.model, endpoint, done.trajectory.status, done.trajectory.error)
        return done

    def keep_unsaved(
        self, spec: EpisodeSpec, unsaved: UnsavedCassette, trajectory: Trajectory, *, retries: int
    ) -> None:
        """Write a live episode whose cassette could not be saved to the run directory's
        :data:`UNSAVED` folder (the cassette, ready to move into place, and the result with its
        retries), and remember the line that says where."""
        folder = self.run_dir / UNSAVED
        traffic, fallback = folder / f"{spec.case_id}.json.xz", folder / f"{spec.case_id}.json"
        cause = os_error_line(
            unsaved.cause, doing="write", path=unsaved.path, option="--emrd-cassettes DIR"
        )
        write_bytes_atomic(traffic, unsaved.blob)
        record = {
            "case_id": spec.case_id,
            "cassette": str(unsaved.path),
            "cause": cause,
            "interactions": str(traffic),
            "retries": retries,
            "trajectory": trajectory.to_dict(),
        }
        write_bytes_atomic(fallback, scrub_bytes(json.dumps(record).encode()))
        move = shlex.join(["mv", str(traffic), str(unsaved.path)])
        parent = shlex.join(["mkdir", "-p", str(unsaved.path.parent)])
        self._unsaved[spec] = (
            f"{spec.case_id}: the cassette {cause} The live episode is kept in {fallback} and "
            f"in the run directory: resume with --emrd-results {self.run_dir} to reuse it "
            f"without calling the model again. Its recorded cassette is {traffic}; to replay "
            f"it offline, fix the cause, then: {parent} && {move}"
        )

    def episode(self, spec: EpisodeSpec) -> StoredEpisode:
        """The stored episode of ``spec``, computed on first use (a failure: one line)."""
        if spec in self._stored:
            return self._stored[spec]
        if not self._prefetch_started:  # --emrd-concurrency: live episodes ahead, in threads
            self._prefetch_started = True
            self._prefetcher = start_prefetch(
                self.settings, self.store, self.compute, self.episode_specs, self.modality_of
            )
        measure = self.gated(spec)  # a gate here reads its metrics: measured with it, once
        stored = self.call(
            lambda run: run.store.get_or_compute(spec, run.compute, measure=measure), spec.case_id
        )
        self._stored[spec] = stored
        if spec in self._unsaved:
            warnings.warn(CassetteNotSavedWarning(scrub(self._unsaved.pop(spec))), stacklevel=2)
        if stored.head.frame_drift and stored.computed_now:
            from pytest_emrd.cassette import FrameDriftWarning

            warnings.warn(
                FrameDriftWarning(
                    f"{spec.case_id}: {stored.head.frame_drift} request(s) matched on text while "
                    "their frames differ from the recording (lenient matching)."
                ),
                stacklevel=2,
            )
        return stored

    def gated(self, spec: EpisodeSpec) -> bool:
        """Whether a gate this process collected reads ``spec``'s metrics (then whoever computes
        or first reuses the episode measures it, once, and every process reads them back)."""
        cells = self.__dict__.get("gate_cells", ())  # parametrised gates only: nothing loaded
        return any(
            (c.bound.model, c.bound.condition) == (spec.model, spec.condition) for c in cells
        )

    def specs_of(self, params: Iterable[EpisodeSpec | GateCell]) -> list[EpisodeSpec]:
        """The episodes behind EMRD test parameters: a spec's own, a gate's whole cell."""
        cells = (
            self.cell_specs_of(p.bound.model, p.bound.condition) if isinstance(p, GateCell) else [p]
            for p in params
        )
        return [spec for cell in cells for spec in cell]

    def cell_specs_of(self, model: str, condition: str) -> list[EpisodeSpec]:
        self.registry.get(model)
        check_choice("condition", condition, CONDITIONS)
        return cell_specs(self.settings, model, condition, self.modality_of)

    def verdict(self, cell: GateCell) -> Verdict:
        from pytest_emrd.metrics import GATE_METRICS

        specs = self.cell_specs_of(cell.bound.model, cell.bound.condition)
        missing = [spec for spec in specs if spec not in self._metrics]
        stored = [self.episode(spec) for spec in missing]  # computed and measured here, if at all
        self._metrics.update(zip(missing, self.store.metrics(stored), strict=True))
        episodes = [self._metrics[spec] for spec in specs]
        run_dir = str(self.run_dir)
        return evaluate_cell(cell, episodes, GATE_METRICS, run_dir_of=lambda case: run_dir)

    def summary(self, stored: StoredEpisode) -> EpisodeSummary:
        config = self.registry.get(stored.head.spec.model)
        return EpisodeSummary.of(
            stored, price_in=config.price_per_mtok_in, price_out=config.price_per_mtok_out
        )

    @pytest.hookimpl(trylast=True)
    def pytest_sessionfinish(self) -> None:
        # An ai2thor simulator owns a Unity process. Closed here, a worker stops it before it
        # tells the controller it has finished (xdist sends that after this hook): at
        # unconfigure, the controller's exit timeout may already kill the worker mid-stop.
        if "executor" in self.__dict__:
            self.executor.simulators.close()

    def pytest_unconfigure(self) -> None:
        if self._prefetcher is not None:
            self._prefetcher.close()
        if "executor" in self.__dict__:
            self.executor.close()  # sessionfinish may not have run (an interrupted start-up)
