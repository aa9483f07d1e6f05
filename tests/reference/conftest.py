"""Drive a scripted agent step by step with hand-made views, as the episode loop would."""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import pytest

from pytest_emrd.agent import build_system_prompt, load_registry, step_text
from pytest_emrd.reference import reply_text
from pytest_emrd.trajectory import Pose
from pytest_emrd.world import VisibleObject
from pytest_emrd.world._feedback import with_pose

#: (id, type, bearing, distance) as the symbolic list gives them.
View = Sequence[tuple[str, str, float, float]]
ORIGIN = Pose(0.0, 0.0, 0.0)


@dataclass
class Driver:
    """One agent's conversation: :meth:`see` sends a view and returns the decoded reply."""

    model: str
    system: str
    step: int = 0
    last: str | None = None
    replies: list[dict[str, Any]] = field(default_factory=list)

    def see(self, view: View, pose: Pose = ORIGIN) -> dict[str, Any]:
        self.step += 1
        text = step_text(
            step=self.step,
            max_steps=50,
            feedback=with_pose("ok", pose),
            visible=[VisibleObject(*v) for v in view],
        )
        messages = [{"role": "system", "content": self.system}]
        if self.last is not None:
            messages.append({"role": "assistant", "content": self.last})
        messages.append({"role": "user", "content": text})
        config = load_registry().get(self.model)
        self.last = reply_text(self.model, config.planted, messages)
        reply = json.loads(self.last)
        self.replies.append(reply)
        return reply


@pytest.fixture
def drive(inventory) -> Callable[[str], Driver]:
    """A fresh conversation with reference agent ``model`` under the default prompt."""

    def make(model: str, variant: str = "default") -> Driver:
        return Driver(model, build_system_prompt(inventory, variant))

    return make
