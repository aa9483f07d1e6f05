"""Protocol per backend, caller-owned simulators, backend options and the simulator pool."""

from __future__ import annotations

from contextlib import closing

import pytest

from pytest_emrd import world
from pytest_emrd.agent import PROMPT_VERSION
from pytest_emrd.episode import (
    SimulatorPool,
    build_simulator,
    protocol_version,
    run_episode,
)
from pytest_emrd.errors import ConfigError
from pytest_emrd.trajectory import EpisodeSpec
from pytest_emrd.world.thor import THOR_VERSION


def _spec(episode: int = 0, **overrides) -> EpisodeSpec:
    fields = {"condition": "baseline", "spawn": "kitchen", "max_steps": 3, "modality": "text"}
    return EpisodeSpec("gemini", episode=episode, **{**fields, **overrides})


def test_builtin_protocol_is_unchanged_and_ai2thor_has_its_own():
    builtin = f"{world.WORLD_VERSION}+{PROMPT_VERSION}"
    assert protocol_version() == protocol_version("builtin") == builtin
    assert protocol_version("ai2thor") == f"{THOR_VERSION}+{builtin}" != builtin


def test_unknown_backend_protocol_names_the_backends():
    with pytest.raises(ConfigError, match="backend='unity' is not one of"):
        protocol_version("unity")


def test_a_caller_owned_simulator_is_reused_and_left_open(scripted, reply, monkeypatch):
    sim = world.BuiltinSimulator()
    closed: list[bool] = []
    monkeypatch.setattr(sim, "close", lambda: closed.append(True))
    runs = [
        run_episode(_spec(k), client=scripted([reply("Turn(Right)")]), simulator=sim)
        for k in (0, 1, 0)
    ]
    assert not closed
    fresh = [run_episode(_spec(k), client=scripted([reply("Turn(Right)")])) for k in (0, 1)]
    assert runs == [fresh[0], fresh[1], fresh[0]]


def test_backend_options_reach_the_simulator(scripted, reply, monkeypatch):
    built: list[dict] = []
    real = world.make_simulator

    def spy(backend: str, **options):
        built.append({"backend": backend, **options})
        return real(backend, **options)

    monkeypatch.setattr(world, "make_simulator", spy)
    run_episode(
        _spec(), client=scripted([reply("Turn(Left)")]), backend_options={"jpeg_quality": 60}
    )
    assert built == [{"backend": "builtin", "jpeg_quality": 60}]


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"gpu_device": 1}, r"backend_options=\{'gpu_device': 1\} do not fit the builtin"),
        ({"jpeg_quality": 0}, "jpeg_quality"),
    ],
    ids=["unknown-key", "bad-value"],
)
def test_bad_backend_options_are_config_errors(options, message):
    with pytest.raises(ConfigError, match=message):
        build_simulator("builtin", options)


def test_simulator_and_backend_options_together_is_a_config_error(scripted, reply):
    with pytest.raises(ConfigError, match="pass only it"):
        run_episode(
            _spec(),
            client=scripted([reply("Turn(Left)")]),
            simulator=world.BuiltinSimulator(),
            backend_options={"jpeg_quality": 60},
        )


def test_the_pool_builds_builtin_per_episode(scripted, reply):
    with closing(SimulatorPool({"jpeg_quality": 60})) as pool:
        first = pool.run(_spec(), client=scripted([reply("Turn(Left)")]))
    assert first == run_episode(_spec(), client=scripted([reply("Turn(Left)")]))


def test_the_pool_keeps_one_thor_controller_across_episodes(fake_thor, scripted, reply):
    fake_thor.instances.clear()
    with closing(SimulatorPool({"controller_factory": fake_thor, "gpu_device": 1})) as pool:
        for k in (0, 1, 2):
            traj = pool.run(_spec(k, backend="ai2thor"), client=scripted([reply("Turn(Right)")]))
            assert traj.status == "budget" and traj.protocol == protocol_version("ai2thor")
        (controller,) = fake_thor.instances
        assert controller.init["gpu_device"] == 1 and not controller.stopped
        assert [a for a, _ in controller.calls].count("reset") == 2
    assert controller.stopped


def test_an_errored_thor_episode_replaces_the_simulator(fake_thor, scripted, reply):
    fake_thor.instances.clear()
    with closing(SimulatorPool({"controller_factory": fake_thor})) as pool:
        broken = pool.run(
            _spec(0, backend="ai2thor"), client=scripted([reply("Turn(Right)")], fail_at=2)
        )
        assert broken.status == "errored" and fake_thor.instances[0].stopped
        again = pool.run(_spec(0, backend="ai2thor"), client=scripted([reply("Turn(Right)")]))
    assert again.status == "budget" and len(fake_thor.instances) == 2
