"""Gates: run settings, the episode grid, the results store, thresholds and verdicts."""

from pytest_emrd.gate._files import load_run_dirs, load_run_episodes, load_thresholds
from pytest_emrd.gate._fingerprint import code_fingerprint
from pytest_emrd.gate._grid import cell_specs, episode_specs, gate_cells, shard
from pytest_emrd.gate._head import EpisodeHead
from pytest_emrd.gate._identity import (
    RunIdentity,
    check_resume,
    check_shard_set,
    read_identity,
    write_identity,
)
from pytest_emrd.gate._measured import (
    EPISODE_METRICS_CODE,
    EPISODE_METRICS_LIBRARIES,
    MeasuredStore,
    measured_episodes,
)
from pytest_emrd.gate._prefetch import Prefetcher, start_prefetch
from pytest_emrd.gate._settings import (
    BACKENDS,
    LENIENT_BACKENDS,
    MATCHING_MODES,
    OPTIONS,
    RECORD_MODES,
    SPAWNS,
    MatchingWarning,
    Option,
    RunSettings,
    parse_backend_option,
    parse_shard,
    resolve_settings,
)
from pytest_emrd.gate._store import (
    ResultsStore,
    StoredEpisode,
    episode_path,
    iter_run_dir,
    iter_run_episodes,
    new_run_dir,
    read_episode,
)
from pytest_emrd.gate._summary import EpisodeSummary, usage_rows
from pytest_emrd.gate._table import UsageRow, gate_tables, usage_table
from pytest_emrd.gate._thresholds import Bound, Thresholds, parse_thresholds
from pytest_emrd.gate._verdict import GateCell, Verdict, evaluate_all, evaluate_cell, judge

__all__ = [
    "BACKENDS",
    "EPISODE_METRICS_CODE",
    "EPISODE_METRICS_LIBRARIES",
    "LENIENT_BACKENDS",
    "MATCHING_MODES",
    "OPTIONS",
    "RECORD_MODES",
    "SPAWNS",
    "Bound",
    "EpisodeHead",
    "EpisodeSummary",
    "GateCell",
    "MatchingWarning",
    "MeasuredStore",
    "Option",
    "Prefetcher",
    "ResultsStore",
    "RunIdentity",
    "RunSettings",
    "StoredEpisode",
    "Thresholds",
    "UsageRow",
    "Verdict",
    "cell_specs",
    "check_resume",
    "check_shard_set",
    "code_fingerprint",
    "episode_path",
    "episode_specs",
    "evaluate_all",
    "evaluate_cell",
    "gate_cells",
    "gate_tables",
    "iter_run_dir",
    "iter_run_episodes",
    "judge",
    "load_run_dirs",
    "load_run_episodes",
    "load_thresholds",
    "measured_episodes",
    "new_run_dir",
    "parse_backend_option",
    "parse_shard",
    "parse_thresholds",
    "read_episode",
    "read_identity",
    "resolve_settings",
    "shard",
    "start_prefetch",
    "usage_rows",
    "usage_table",
    "write_identity",
]
