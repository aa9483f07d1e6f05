"""The episode loop: one :class:`EpisodeSpec` in, one :class:`Trajectory` out.

Per step ``t`` (see :mod:`pytest_emrd.trajectory` for the timeline): the observation
``o_{t-1}`` is rendered into a user message (frame as a JPEG data URL in ``vision`` and
``both``, engine feedback, pose, "Step t of T", and the symbolic list in ``text`` and
``both``), the windowed conversation is sent to the model, the reply is parsed, a ``Term``
room alias is resolved to the canonical room, and the world executes the action. The
step records the pose, room and visible ids of ``o_{t-1}``, the map ``M_t`` (the previous
map when the reply could not be read), the action and its outcome.

Nothing is lost: a transport failure or any crash inside the loop ends the episode as
``errored`` with the cause, keeping every completed step. Misconfiguration found before
the first step (unknown model, missing API key, bad spec) raises :class:`ConfigError`.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from pytest_emrd import frames, world
from pytest_emrd.agent import (
    PROMPT_VERSION,
    ChatClient,
    Conversation,
    Registry,
    UserTurn,
    build_system_prompt,
    load_registry,
    make_client,
    parse_reply,
    resolve_room,
    step_text,
)
from pytest_emrd.errors import check_choice, check_positive_int
from pytest_emrd.rooms import SLUG_ROOMS
from pytest_emrd.trajectory import (
    CONDITIONS,
    MODALITIES,
    VARIANTS,
    EpisodeSpec,
    MapEntry,
    Step,
    Trajectory,
)
from pytest_emrd.world._model import Observation, Simulator

_TERM = re.compile(r"^\s*term\s*\(\s*(?P<room>.*?)\s*\)\s*\.?\s*$", re.IGNORECASE | re.DOTALL)


def protocol_version() -> str:
    """World + prompt protocol version; cassettes and stored results are keyed by it."""
    return f"{world.WORLD_VERSION}+{PROMPT_VERSION}"


def _check_spec(spec: EpisodeSpec) -> None:
    check_choice("condition", spec.condition, CONDITIONS)
    check_choice("variant", spec.variant, VARIANTS)
    check_choice("modality", spec.modality, MODALITIES)
    check_choice("spawn", spec.spawn, SLUG_ROOMS)
    check_positive_int("max_steps", spec.max_steps)


def world_action(action: str, variant: str) -> tuple[str, str | None]:
    """(text the world executes, raw Term room or None): Term aliases become canonical."""
    match = _TERM.match(action)
    if match is None:
        return action, None
    raw = match["room"]
    canonical = resolve_room(raw, variant)
    return (f"Term({canonical})" if canonical else action), raw


def _user_turn(spec: EpisodeSpec, step: int, obs: Observation) -> UserTurn:
    symbolic = obs.visible if spec.modality in ("text", "both") else None
    text = step_text(
        step=step, max_steps=spec.max_steps, feedback=obs.feedback, pose=obs.pose, visible=symbolic
    )
    if spec.modality == "text":
        return UserTurn(step, text)
    turn = UserTurn.with_frame(step, text, obs.jpeg, obs.frame_digest)
    frames.register(turn.jpeg_b64 or "", obs.frame_digest)  # before any request carries it
    return turn


class _Run:
    """Mutable state of one episode while it runs."""

    def __init__(self, spec: EpisodeSpec, sim: Simulator, conversation: Conversation) -> None:
        self.spec, self.sim, self.conversation = spec, sim, conversation
        self.steps: list[Step] = []
        self.belief: tuple[MapEntry, ...] = ()
        self.chosen_room: str | None = None
        self.chosen_raw: str | None = None
        self.rationale: str | None = None

    def step(self, t: int, obs: Observation, client: ChatClient) -> tuple[Step, Observation]:
        pose, room, visible = obs.pose, self.sim.current_room(), self.sim.visible_ids()
        turn = _user_turn(self.spec, t, obs)
        messages = self.conversation.request(turn)
        response = client.complete(messages)
        reply = parse_reply(response.text)
        if reply.error is None:
            self.belief = reply.cognitive_map
        action, term_raw = world_action(reply.action, self.spec.variant)
        after = self.sim.step(action)
        self.conversation.record(turn, response.text)
        if term_raw is not None:
            self.chosen_raw, self.rationale = term_raw, reply.reasoning
            self.chosen_room = after.terminal_room if after.done else None
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
            raw_reply=response.text,
            usage=response.usage,
        )
        self.steps.append(step)
        return step, after


def run_episode(
    spec: EpisodeSpec,
    *,
    registry: Registry | None = None,
    client: ChatClient | None = None,
    on_step: Callable[[Step], None] | None = None,
) -> Trajectory:
    """Run one episode of ``spec`` against its model and return the full trajectory.

    ``client`` overrides the client built from the registry (the caller keeps ownership);
    ``on_step`` is called with every completed step (progress lines, live plots).
    """
    _check_spec(spec)
    config = (registry or load_registry()).get(spec.model)
    spawn_room = SLUG_ROOMS[spec.spawn]
    layout = world.generate_layout(spec.seed)
    sim = world.make_simulator(spec.backend)
    own_client = client is None
    status, error = "budget", None
    try:
        obs = sim.reset(layout, spec.condition, spawn_room, spec.seed)
        truth = world.ground_truth(layout, sim.spawn_pose, spawn_room)
        system = build_system_prompt(layout.inventory(), spec.variant, max_steps=spec.max_steps)
        run = _Run(spec, sim, Conversation(system, single_image=config.single_image))
        active = client or make_client(config)
        try:
            for t in range(1, spec.max_steps + 1):
                step, obs = run.step(t, obs, active)
                if on_step is not None:
                    on_step(step)
                if obs.done:
                    status = "terminated" if obs.terminal_room is not None else "budget"
                    break
        except Exception as exc:  # contract: a crash ends this episode as errored, not the run
            status, error = "errored", f"{type(exc).__name__}: {exc}"
        finally:
            if own_client:
                active.close()
        final_room = sim.current_room()
    finally:
        sim.close()
    return Trajectory(
        spec=spec,
        protocol=protocol_version(),
        ground_truth=truth,
        steps=tuple(run.steps),
        status=status,
        final_room=final_room,
        chosen_room=run.chosen_room if status == "terminated" else None,
        chosen_room_raw=run.chosen_raw,
        rationale=run.rationale,
        error=error,
    )
