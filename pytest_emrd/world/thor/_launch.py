"""Starting AI2-THOR: the lazy import, cheap pre-flight checks, and a bounded start-up.

Everything here fails fast with a message that says what to install or set:

* ``ai2thor`` not installed -> :func:`pytest_emrd.errors.missing_extra` (``thor`` extra);
* ``local_executable_path`` missing or not executable;
* ``platform=CloudRendering`` without a Vulkan loader -> install ``libvulkan1``;
* no THOR build for this ai2thor commit under ``~/.ai2thor/releases`` (and downloads not
  allowed) -> download once or pass ``local_executable_path``;
* a Unity process that exits or never answers -> bounded by ``start_timeout``.

No pre-flight check touches the network; a build download happens only when the caller
passes ``allow_download=True``, and then still under the start-up time limit.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from types import ModuleType
from typing import Any

from pytest_emrd.errors import ConfigError, missing_extra
from pytest_emrd.world.thor._watchdog import bounded

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


def _platform_name(platform: Any) -> str:
    return platform if isinstance(platform, str) else getattr(platform, "__name__", str(platform))


def preflight(thor: ModuleType, options: Mapping[str, Any], *, allow_download: bool) -> None:
    """Cheap local checks before any Unity process is launched (see module docstring)."""
    local = options.get("local_executable_path")
    if local:
        if not os.path.isfile(local) or not os.access(local, os.X_OK):
            raise ConfigError(
                f"local_executable_path={local!r} is not an executable file; point it at the "
                "thor-<platform>-<commit> executable inside an unpacked AI2-THOR build."
            )
        return
    platform = options.get("platform")
    if platform is None or _platform_name(platform) != "CloudRendering":
        return
    request = thor.platform.Request(
        "Linux", options.get("width", 300), options.get("height", 300), None, False
    )
    problems = thor.platform.CloudRendering.validate(request)
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


def start(factory: Callable[..., Any], options: Mapping[str, Any], *, seconds: float) -> Any:
    """``factory(**options)`` within ``seconds``, start-up failures turned into ConfigError."""

    def on_timeout() -> ConfigError:
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
