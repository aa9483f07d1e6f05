"""Starting AI2-THOR: the lazy import, cheap pre-flight checks, and bounded calls.

Everything here fails fast with a message that says what to install or set; no pre-flight
check touches the network. ``Controller.stop_unity`` kills only the one process it started,
and nothing when the constructor never returns: hence ``setsid`` (``docs/ai2thor.md``).
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import threading
from collections.abc import Callable, Mapping
from concurrent.futures import Future, wait
from types import ModuleType
from typing import Any, TypeVar

from pytest_emrd.errors import ConfigError, EmrdError, missing_extra

T = TypeVar("T")

VULKAN_HINT = (
    "CloudRendering renders headless through Vulkan and needs an NVIDIA GPU with its driver "
    "and the Vulkan loader: sudo apt-get install -y libvulkan1 (check with vulkaninfo)."
)
BUILD_HINT = (
    'Download the build once on a machine with network access: python -c "from '
    "ai2thor.controller import Controller; from ai2thor.platform import CloudRendering; "
    'Controller(platform=CloudRendering, download_only=True)" (or pass allow_download=True), '
    "or pass local_executable_path='/path/to/thor-<platform>-<commit>/thor-<platform>-<commit>'."
)


def bounded(fn: Callable[[], T], *, seconds: float, on_timeout: Callable[[], EmrdError]) -> T:
    """``fn()``, or the error ``on_timeout()`` builds if it has not returned in ``seconds``;
    exceptions raised by ``fn`` propagate unchanged."""
    future: Future[T] = Future()

    def target() -> None:
        try:
            future.set_result(fn())
        except BaseException as exc:  # handed to the caller's thread by result()
            future.set_exception(exc)

    threading.Thread(target=target, name="emrd-thor-call", daemon=True).start()
    if not wait([future], timeout=seconds).done:
        raise on_timeout()
    return future.result()


def import_ai2thor() -> ModuleType:
    """The ``ai2thor`` package with its controller, platform and build modules loaded."""
    try:
        import ai2thor
        import ai2thor.build
        import ai2thor.controller
        import ai2thor.platform
    except ImportError as exc:
        raise missing_extra("ai2thor", "thor") from exc
    return ai2thor


def releases_dir() -> str:
    """Where ai2thor unpacks downloaded builds (``Controller.releases_dir``)."""
    return os.path.join(os.path.expanduser("~"), ".ai2thor", "releases")


def preflight(thor: ModuleType, options: Mapping[str, Any], *, allow_download: bool) -> None:
    """Cheap local checks before any Unity process is launched."""
    local = options.get("local_executable_path")
    if local:
        if not os.path.isfile(local) or not os.access(local, os.X_OK):
            raise ConfigError(
                f"local_executable_path={local!r} is not an executable file; point it at the "
                "thor-<platform>-<commit> executable inside an unpacked AI2-THOR build."
            )
        return
    platform = options.get("platform")  # a class, or its name
    if getattr(platform, "__name__", str(platform)) != "CloudRendering":
        return
    width, height = options.get("width", 300), options.get("height", 300)
    problems = thor.platform.CloudRendering.validate(
        thor.platform.Request("Linux", width, height, None, False)
    )
    if problems:
        raise ConfigError(
            f"AI2-THOR platform=CloudRendering cannot run here ({' '.join(problems)}). "
            + VULKAN_HINT
        )
    if allow_download:
        return
    commit = options.get("commit_id") or thor.build.COMMIT_ID
    build = thor.build.Build(thor.platform.CloudRendering, commit, False, releases_dir())
    if not os.path.isdir(build.base_dir):
        raise ConfigError(
            f"no AI2-THOR build {build.name} in {releases_dir()} (ai2thor "
            f"{thor.__version__} wants commit_id={commit}). {BUILD_HINT}"
        )


def headless_options(options: Mapping[str, Any]) -> dict[str, Any]:
    """``options`` with ``x_display`` set for a local build when no display is known."""
    out = dict(options)
    local = out.get("local_executable_path")
    if local and not out.get("x_display") and not os.environ.get("DISPLAY"):
        out["x_display"] = ":0"
    return out


def launcher(base: type, started: list[Any]) -> type:
    """``base`` (ai2thor's Controller) launching Unity under ``setsid``; every instance is
    appended to ``started`` before its constructor starts Unity."""
    setsid = shutil.which("setsid")

    class Launcher(base):  # type: ignore[misc, valid-type]
        def __init__(self, **options: Any) -> None:
            started.append(self)
            super().__init__(**options)

        def unity_command(self, width: int, height: int, headless: bool) -> list[str]:
            command = list(super().unity_command(width, height, headless))
            return [setsid, *command] if setsid else command

    Launcher.__name__ = Launcher.__qualname__ = base.__name__
    return Launcher


def kill_unity(controller: Any) -> None:
    """Kill the Unity process of ``controller`` and, if it leads one, its process group."""
    proc = getattr(getattr(controller, "server", None), "unity_proc", None)
    if not isinstance(proc, subprocess.Popen) or proc.poll() is not None:
        return
    try:
        group = os.getpgid(proc.pid)
        if group == proc.pid and group != os.getpgrp():
            os.killpg(group, signal.SIGKILL)
        else:
            proc.kill()
        proc.wait(timeout=5)
    except (ProcessLookupError, subprocess.TimeoutExpired):
        return


def _translate(exc: BaseException) -> ConfigError:
    text = str(exc)
    lowered = text.lower()
    if "no build exists" in lowered or "invalid commit_id" in lowered:
        return ConfigError(f"AI2-THOR found no build: {text}. {BUILD_HINT}")
    if "vulkan" in lowered or "unity process has exited" in lowered:
        return ConfigError(f"the AI2-THOR Unity process could not start: {text}. {VULKAN_HINT}")
    if isinstance(exc, TimeoutError):
        return ConfigError(f"the AI2-THOR Unity process did not answer: {text}. {VULKAN_HINT}")
    return ConfigError(f"AI2-THOR failed to start: {type(exc).__name__}: {text}")


def start(
    factory: Callable[..., Any], options: Mapping[str, Any], *, seconds: float, started: list[Any]
) -> Any:
    """``factory(**options)`` within ``seconds``, start-up failures turned into ConfigError.

    On a timeout, the Unity process of every controller in ``started`` (filled by a
    :func:`launcher` class) is killed with its process group before the error is raised.
    """

    def on_timeout() -> ConfigError:
        for controller in started:
            kill_unity(controller)
        return ConfigError(
            f"AI2-THOR did not start within start_timeout={seconds:g} s (no answer from the "
            f"Unity process). {VULKAN_HINT} If the build is still downloading, download it "
            f"first. {BUILD_HINT}"
        )

    try:
        return bounded(lambda: factory(**options), seconds=seconds, on_timeout=on_timeout)
    except ConfigError:
        raise
    except Exception as exc:
        raise _translate(exc) from exc
