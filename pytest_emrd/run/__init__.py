"""A run: its settings, the episode grid, the results store of its directory, prefetch (it
feeds :mod:`pytest_emrd.gate` and uses ``cassette``; neither imports it)."""

from pytest_emrd.run._grid import cell_specs, episode_specs, gate_cells, shard
from pytest_emrd.run._identity import (
    RunIdentity,
    check_resume,
    check_shard_set,
    read_identity,
    scratch_dir,
    write_identity,
)
from pytest_emrd.run._prefetch import Prefetcher, start_prefetch
from pytest_emrd.run._settings import OPTIONS, MatchingWarning, RunSettings, resolve_settings
from pytest_emrd.run._store import (
    EpisodeHead,
    ResultsStore,
    StoredEpisode,
    episode_path,
    load_run_dirs,
    load_run_episodes,
    measure_episodes,
    new_run_dir,
    read_episode,
)
from pytest_emrd.run._summary import EpisodeSummary, usage_rows
from pytest_emrd.trajectory import RECORD_MODES

__all__ = [
    "OPTIONS",
    "RECORD_MODES",
    "EpisodeHead",
    "EpisodeSummary",
    "MatchingWarning",
    "Prefetcher",
    "ResultsStore",
    "RunIdentity",
    "RunSettings",
    "StoredEpisode",
    "cell_specs",
    "check_resume",
    "check_shard_set",
    "episode_path",
    "episode_specs",
    "gate_cells",
    "load_run_dirs",
    "load_run_episodes",
    "measure_episodes",
    "new_run_dir",
    "read_episode",
    "read_identity",
    "resolve_settings",
    "scratch_dir",
    "shard",
    "start_prefetch",
    "usage_rows",
    "write_identity",
]
