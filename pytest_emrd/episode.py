"""The episode loop: one :class:`EpisodeSpec` in, one :class:`Trajectory` out.

Per step ``t`` (timeline: :mod:`pytest_emrd.trajectory`) the observation ``o_{t-1}`` becomes a
user message (frame in ``vision``/``both``, the symbolic list in ``text``/``both``), the
windowed conversation goes to the model, the reply is parsed, a ``Term`` room alias is
resolved and the world executes the action. ``Term(r)`` always ends the episode
(``terminated``); ``r`` outside the four rooms leaves ``chosen_room`` None (focal column X),
``r`` kept in ``chosen_room_raw``. An unreadable reply keeps the previous map.

A transport failure or any crash inside the loop ends the episode as ``errored`` with the
cause, keeping every completed step; misconfiguration found before the first step raises
:class:`ConfigError`. A caller-owned ``simulator`` is reset per episode and left open, so
one AI2-THOR process serves every episode of a worker.
"""

from __future__ import annotations

import os
import re
import threading
import time
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, Final

from pytest_emrd import frames, reference, world
from pytest_emrd._files import os_error_line
from pytest_emrd._wire import encode_body
from pytest_emrd.agent import (
    JPEG_DATA_URL,
    MAX_REPLY_CHARS,
    ChatClient,
    Conversation,
    ModelConfig,
    Registry,
    UserTurn,
    build_system_prompt,
    load_registry,
    make_client,
    parse_reply,
    resolve_room,
    step_text,
)
from pytest_emrd.cassette import EpisodeRun, Tape, canonical_body
from pytest_emrd.errors import (
    CassetteError,
    ConfigError,
    EmrdError,
    check_choice,
    check_positive_int,
)
from pytest_emrd.protocol import protocol_version
from pytest_emrd.rooms import SLUG_ROOMS
from pytest_emrd.trajectory import (
    CONDITIONS,
    LAYOUTS,
    MODALITIES,
    VARIANTS,
    EpisodeSpec,
    MapEntry,
    Step,
    Trajectory,
)
from pytest_emrd.world import Observation, Simulator

_TERM = re.compile(r"^\s*term\s*\(\s*(?P<room>.*?)\s*\)\s*\.?\s*$", re.IGNORECASE | re.DOTALL)


#: Backends whose simulator :class:`SimulatorPool` keeps (a Unity process takes seconds to
#: start); ``builtin`` is cheap, and a fresh one keeps its recorded traffic as it was.
REUSED_BACKENDS: Final[frozenset[str]] = frozenset({"ai2thor"})


def build_simulator(backend: str, options: Mapping[str, Any] | None = None) -> Simulator:
    """A new simulator of ``backend`` built with ``options`` (``--emrd-backend-option``); an
    option the backend does not take is a :class:`ConfigError` naming it."""
    options = dict(options or {})
    try:
        return world.make_simulator(backend, **options)
    except TypeError as exc:
        raise ConfigError(
            f"backend_options={options!r} do not fit the {backend} simulator ({exc}); "
            "check the --emrd-backend-option keys against that backend's documentation."
        ) from exc


def _check_spec(spec: EpisodeSpec) -> None:
    check_choice("condition", spec.condition, CONDITIONS)
    check_choice("variant", spec.variant, VARIANTS)
    check_choice("modality", spec.modality, MODALITIES)
    check_choice("spawn", spec.spawn, SLUG_ROOMS)
    check_choice("layouts", spec.layouts, LAYOUTS)
    check_positive_int("max_steps", spec.max_steps)


def world_action(action: str, variant: str) -> tuple[str, str | None]:
    """(text the world executes, raw Term room or None): Term aliases become canonical."""
    match = _TERM.match(action)
    if match is None:
        return action, None
    raw = match["room"]
    canonical = resolve_room(raw, variant)
    return (f"Term({canonical})" if canonical else action), raw


def capped_reply(text: str) -> str:
    """The reply as kept: whole up to :data:`~pytest_emrd.agent._parse.MAX_REPLY_CHARS` (longer
    ones are parse failures), else its head and its full length (bounded memory and disk)."""
    if len(text) <= MAX_REPLY_CHARS:
        return text
    return text[:MAX_REPLY_CHARS] + f"\n[... truncated: the reply had {len(text)} characters]"


def user_turn(spec: EpisodeSpec, step: int, obs: Observation, *, replay: bool = False) -> UserTurn:
    """The user turn of step ``step`` showing ``obs`` as ``spec``'s modality asks; in a
    ``replay`` the frame travels as its pixel digest and its JPEG is never encoded."""
    symbolic = obs.visible if spec.modality in ("text", "both") else None
    text = step_text(step=step, max_steps=spec.max_steps, feedback=obs.feedback, visible=symbolic)
    if spec.modality == "text":
        return UserTurn(step, text)
    if replay:
        return UserTurn.replayed(step, text, obs.frame_digest)
    turn = UserTurn.with_frame(step, text, obs.jpeg, obs.frame_digest)
    url = turn.image_url or ""
    # Before any request carries it; the redactor then finds the frame by its payload.
    frames.register(url.removeprefix(JPEG_DATA_URL), obs.frame_digest)
    return turn


class _Run:
    """Mutable state of one episode while it runs (``replay``: see :func:`user_turn`)."""

    def __init__(
        self, spec: EpisodeSpec, sim: Simulator, conversation: Conversation, *, replay: bool
    ) -> None:
        self.spec, self.sim, self.conversation, self.replay = spec, sim, conversation, replay
        self.steps: list[Step] = []
        self.belief: tuple[MapEntry, ...] = ()
        self.chosen_room: str | None = None
        self.chosen_raw: str | None = None
        self.rationale: str | None = None

    def step(self, t: int, obs: Observation, client: ChatClient) -> tuple[Step, Observation]:
        pose, room, visible = obs.pose, self.sim.current_room(), self.sim.visible_ids()
        turn = user_turn(self.spec, t, obs, replay=self.replay)
        messages = self.conversation.request(turn)
        start = time.perf_counter()
        response = client.complete(messages)
        latency = None if self.replay else round(time.perf_counter() - start, 3)
        reply = parse_reply(response.text)
        raw = capped_reply(response.text)
        if reply.error is None:
            self.belief = reply.cognitive_map
        action, term_raw = world_action(reply.action, self.spec.variant)
        after = self.sim.step(action)
        self.conversation.record(turn, raw)
        if term_raw is not None and after.done:
            self.chosen_raw, self.rationale = term_raw, reply.reasoning
            self.chosen_room = after.terminal_room
        step = Step(
            index=t,
            pose=pose,
            room=room,
            visible_ids=tuple(sorted(visible)),
            cognitive_map=self.belief,
            action=reply.action,
            success=after.success,
            feedback=after.feedback,
            parse_error=reply.error,
            raw_reply=raw,
            usage=response.usage,
            repairs=reply.repairs,
            latency_s=latency,
        )
        self.steps.append(step)
        return step, after


def start_world(spec: EpisodeSpec, sim: Simulator) -> tuple[world.Layout, Observation]:
    """The world of ``spec`` on ``sim`` (:func:`pytest_emrd.world.episode_world`): its layout
    and ``o_0``; under ``vision`` no object id is named. The loop and the viewer start here."""
    episode = world.episode_world(spec)
    obs = sim.reset(
        episode.layout,
        spec.condition,
        episode.spawn_room,
        episode.seed,
        symbolic=spec.modality != "vision",
    )
    return episode.layout, obs


def run_episode(
    spec: EpisodeSpec,
    *,
    registry: Registry | None = None,
    client: ChatClient | None = None,
    on_step: Callable[[Step], None] | None = None,
    simulator: Simulator | None = None,
    backend_options: Mapping[str, Any] | None = None,
    replay: bool = False,
) -> Trajectory:
    """Run one episode of ``spec`` against its model and return the full trajectory.

    ``client`` overrides the registry's client (the caller keeps ownership); ``on_step`` sees
    every completed step. ``simulator`` (caller-owned, not closed) or else one built from
    ``backend_options`` and closed at the end; both at once is a :class:`ConfigError`.
    ``replay``: a cassette answers every request, so frames travel as pixel digests.
    """
    _check_spec(spec)
    if simulator is not None and backend_options:
        raise ConfigError(
            f"run_episode got simulator= and backend_options={dict(backend_options)!r}; "
            "build the simulator with those options (world.make_simulator) and pass only it."
        )
    config = (registry or load_registry()).get(spec.model)
    own_sim = simulator is None
    sim = build_simulator(spec.backend, backend_options) if own_sim else simulator
    own_client = client is None
    status, error = "budget", None
    try:
        layout, obs = start_world(spec, sim)
        truth = world.ground_truth(layout, sim.spawn_pose, SLUG_ROOMS[spec.spawn])
        system = build_system_prompt(
            layout.inventory(), spec.variant, modality=spec.modality, max_steps=spec.max_steps
        )
        conversation = Conversation(system, single_image=config.single_image)
        run = _Run(spec, sim, conversation, replay=replay)
        active = client or make_client(config, base_url=reference.base_url_of(config))
        try:
            for t in range(1, spec.max_steps + 1):
                step, obs = run.step(t, obs, active)
                if on_step is not None:
                    on_step(step)
                if obs.done:
                    status = "terminated"
                    break
        except Exception as exc:  # contract: a crash ends this episode as errored, not the run
            status, error = "errored", f"{type(exc).__name__}: {exc}"
        finally:
            if own_client:
                active.close()
        final_room = sim.current_room()
    finally:
        if own_sim:
            sim.close()
    return Trajectory(
        spec=spec,
        protocol=protocol_version(spec.backend),
        ground_truth=truth,
        steps=tuple(run.steps),
        status=status,
        final_room=final_room,
        chosen_room=run.chosen_room if status == "terminated" else None,
        chosen_room_raw=run.chosen_raw,
        rationale=run.rationale,
        error=error,
    )


class SimulatorPool:
    """Simulators kept across episodes, one per backend of :data:`REUSED_BACKENDS`.

    ``pool.run(spec, ...)`` is :func:`run_episode` on the pooled simulator (built with
    ``options`` on first use) or a fresh one for other backends. A simulator that saw an
    errored episode or an exception is rebuilt, so a dead Unity process costs one episode.
    The owner calls :meth:`close`.
    """

    def __init__(self, options: Mapping[str, Any] | None = None) -> None:
        self._options = dict(options or {})
        self._live: dict[str, Simulator] = {}

    def run(self, spec: EpisodeSpec, **kwargs: Any) -> Trajectory:
        """:func:`run_episode` of ``spec`` with ``kwargs`` (``registry``, ``client``, ...)."""
        if spec.backend not in REUSED_BACKENDS:
            return run_episode(spec, backend_options=self._options, **kwargs)
        sim = self._live.get(spec.backend)
        if sim is None:
            sim = self._live[spec.backend] = build_simulator(spec.backend, self._options)
        try:
            trajectory = run_episode(spec, simulator=sim, **kwargs)
        except BaseException:
            self.discard(spec.backend)
            raise
        if trajectory.status == "errored":
            self.discard(spec.backend)
        return trajectory

    def discard(self, backend: str) -> None:
        """Close and forget the simulator of ``backend`` (a failing close only warns)."""
        sim = self._live.pop(backend, None)
        if sim is None:
            return
        try:
            sim.close()
        except EmrdError as exc:
            warnings.warn(f"closing the {backend} simulator failed: {exc}", stacklevel=2)

    def close(self) -> None:
        """Close every pooled simulator."""
        for backend in list(self._live):
            self.discard(backend)


class Executor:
    """Runs the episodes of one process: :meth:`tape` decides live or replay, :meth:`run` opens
    the cassette, runs the loop and hands back the run; ``on_step`` sees every step.

    One model client per model and key mode (a replay's without a key: recorded requests carry
    none) and the :class:`SimulatorPool` serve every episode until :meth:`close`.
    ``cassettes``, ``record_mode`` ... are the :class:`~pytest_emrd.cassette.Tape` options of
    every episode."""

    def __init__(
        self,
        registry: Registry,
        *,
        backend_options: Mapping[str, Any] | None = None,
        **cassettes: Any,
    ) -> None:
        self.registry = registry
        self.simulators = SimulatorPool(backend_options)
        self._cassettes = cassettes
        self._clients: dict[tuple[str, bool], ChatClient] = {}
        self._lock = threading.Lock()

    def tape(self, spec: EpisodeSpec) -> Tape:
        """``spec``'s cassette, and whether running it calls the model (decided here, once)."""
        return Tape(spec, **self._cassettes)

    def run(self, tape: Tape, *, on_step: Callable[[Step], None] | None = None) -> EpisodeRun:
        """The episode of ``tape`` run through its cassette. Live, its cassette folder must be
        writable first (else nothing is sent to the model: a :class:`CassetteError`)."""
        spec = tape.spec
        if tape.live:
            _check_writable(tape.path)
        client = self._client(spec.model, tape.live)
        for take in tape.takes():
            with take:
                take.trajectory = self.simulators.run(
                    spec,
                    registry=self.registry,
                    client=client,
                    on_step=on_step,
                    replay=not tape.live,
                )
        return take.result

    def close(self) -> None:
        """Close every client and simulator now."""
        for client in self._clients.values():
            client.close()
        self._clients.clear()
        self.simulators.close()

    def _client(self, model: str, live: bool) -> ChatClient:
        with self._lock:
            client = self._clients.get((model, live))
            if client is None:
                client = self._clients[(model, live)] = episode_client(
                    self.registry.get(model), live=live
                )
        return client


def episode_client(config: ModelConfig, *, live: bool) -> ChatClient:
    """The client an episode of ``config`` sends through: live, with its API key and a deadline
    on each attempt; a replay's with neither (recorded requests carry no key, and the cassette
    answers before any connection is made), sending each request in the canonical form its
    recording holds (:func:`~pytest_emrd.cassette.canonical_body`).

    :param config: The model's registry entry.
    :param live: Whether the episode calls the model.
    :returns: A new client; the caller closes it.
    """
    url = reference.base_url_of(config)
    encode = encode_body if live else canonical_body
    return make_client(config, base_url=url, require_key=live, deadline=live, encode=encode)


def _check_writable(path: Path) -> None:
    """Raise the :class:`CassetteError` writing ``path`` would meet (nothing is created)."""
    folder = path.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        error: OSError = NotADirectoryError(20, "Not a directory", str(folder))
    elif not os.access(folder, os.W_OK | os.X_OK):
        error = PermissionError(13, "Permission denied", str(folder))
    else:
        return
    line = os_error_line(error, doing="write", path=path, option="--emrd-cassettes DIR")
    raise CassetteError(f"the cassette {line} Nothing was sent to the model.")
