"""One episode's vcrpy cassette: redaction, matching, record modes and drift detection."""

from __future__ import annotations

import copy
import functools
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Final

from vcr import filters
from vcr.cassette import Cassette
from vcr.record_mode import RecordMode
from vcr.request import Request

from pytest_emrd import _wire
from pytest_emrd._scrub import scrub_bytes, scrub_uri, secret_values
from pytest_emrd.cassette import _routing
from pytest_emrd.cassette._drift import (
    drift_message,
    request_modality,
    unreadable_message,
)
from pytest_emrd.cassette._persister import EpisodePersister
from pytest_emrd.cassette._redact import MatchKeys, match_keys, redact_body, scrub_headers

#: Response headers kept in a cassette (the body is stored decoded, so no Content-Encoding).
KEPT_RESPONSE_HEADERS: Final = frozenset({"content-type"})


def clear_caches() -> None:
    """Forget every cached message encoding and redaction, as at the start of a run
    (cold benchmarks, tests)."""
    _wire.clear()


def _match_keys(request: Request) -> MatchKeys:
    return match_keys(request.method, request.path, redact_body(request.body))


@functools.lru_cache(maxsize=64)
def _scrubbed_uri(uri: str, secrets: tuple[str, ...]) -> str:
    """:func:`scrub_uri` of ``uri``, once per URI and set of configured keys (``secrets`` is
    the cache key: an episode posts every request to one URI)."""
    return scrub_uri(uri)


def redact_request(request: Request) -> Request:
    """vcrpy ``before_record_request``: canonical body, secrets dropped, match keys attached."""
    uri = _scrubbed_uri(request.uri, secret_values())
    if uri != request.uri:  # vcrpy parses the URI again on every assignment
        request.uri = uri
    keys = _match_keys(request)
    request.body = keys.redacted.body
    request.headers = scrub_headers(request.headers)
    request.emrd_keys = keys  # type: ignore[attr-defined]
    return request


def keep_response(response: dict[str, Any]) -> dict[str, Any] | None:
    """vcrpy ``before_record_response``: drop non-2xx responses and volatile headers, and
    remove configured key values from the body."""
    if not 200 <= int(response["status"]["code"]) < 300:
        return None
    response["headers"] = {
        k: v for k, v in response["headers"].items() if k.lower() in KEPT_RESPONSE_HEADERS
    }
    body = response.get("body", {}).get("string")
    if isinstance(body, bytes | str):
        raw = body.encode() if isinstance(body, str) else body
        clean = scrub_bytes(raw, literal_only=True)
        if clean != raw:
            response["body"]["string"] = clean
    return response


def _keys(request: Request) -> MatchKeys:
    keys = getattr(request, "emrd_keys", None)
    if keys is None:
        keys = request.emrd_keys = _match_keys(request)  # type: ignore[attr-defined]
    return keys


def make_matcher(matching: str, frame_drift: set[tuple[Any, Any]]) -> Callable[..., bool]:
    """The one vcrpy matcher: strict or lenient key equality (unparseable never matches).

    In lenient mode a match whose frames differ adds the pair of strict keys to
    ``frame_drift`` so the caller can warn about it.
    """

    def emrd_body(new: Request, recorded: Request) -> bool:
        a, b = _keys(new), _keys(recorded)
        if matching == "strict":
            return a.strict is not None and a.strict == b.strict
        same = a.lenient is not None and a.lenient == b.lenient
        if same and a.strict != b.strict:
            frame_drift.add((a.strict, b.strict))
        return same

    return emrd_body


def _size(strict: tuple[str, bytes]) -> tuple[str, int]:
    return strict[0], len(strict[1])


class EpisodeCassette(Cassette):
    """A vcrpy cassette that remembers why a replay failed (see :mod:`._drift`).

    Requests are counted in the order they are made; the first one that cannot be played
    while the cassette is write-protected is explained: as an unreadable recorded response
    when it repeats a request whose response was already played (the client retried it),
    otherwise as drift against the recorded request at the same position.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.requests_made = 0
        self.drift: str | None = None
        self.frame_drift: set[tuple[Any, Any]] = set()
        self.strict = False
        """Matching is strict: recorded interactions are looked up by strict key."""
        self.rerecord_command = ""
        self.unreadable = False
        """The failure is a recorded response the client could not read (not drift)."""
        self.stop_on_drift = False
        """``new_episodes``: a request the recording does not hold stops the episode (it is
        then recorded again whole) instead of being appended to the recording."""
        self._by_size: dict[tuple[str, int], list[int]] = {}
        self._indexed = 0
        self._loading = False
        self._loaded = 0

    def _load(self) -> None:
        self._loading = True
        try:
            super()._load()
        finally:
            self._loading = False
            self._loaded = len(self.data)

    def append(self, request: Request, response: dict[str, Any]) -> None:
        """vcrpy's ``append``, keeping only the replies that counted.

        A request recorded again right after itself is a retry: the client sends the same
        bytes again only when it could not read the reply (an empty or invalid-JSON 200;
        other failures are never recorded). The reply it could not read is replaced by the
        new one, so a replay gets the good reply first: no retry, no backoff sleep. An
        interaction read back from our own file is not deep-copied first (vcrpy protects a
        live response that way; the decoder built this one for this cassette alone).
        """
        if not self._loading:
            response = copy.deepcopy(response)
        kept = self._before_record_request(request), self._before_record_response(response)
        if not kept[0] or kept[1] is None:
            return
        if not self._loading and self._retried(kept[0]):
            self.data[-1] = kept
        else:
            self.data.append(kept)
        self.dirty = True

    def _retried(self, request: Request) -> bool:
        """Whether ``request`` repeats the last interaction recorded live (not one read back
        from the file, which a replay plays before any request is recorded)."""
        if len(self.data) <= self._loaded:
            return False
        key = _keys(request).strict
        return key is not None and key == _keys(self.data[-1][0]).strict

    def _responses(self, request: Request) -> Iterator[tuple[int, dict[str, Any]]]:
        """vcrpy's lookup (every recorded request tried in turn, for each request made),
        replaced under strict matching by an index on method, path and body length, whose
        few candidates are compared whole: the same interactions, in the same order,
        without a quadratic scan of the episode or a hash of every body."""
        if not self.strict:
            yield from super()._responses(request)
            return
        for index in range(self._indexed, len(self.data)):
            key = _keys(self.data[index][0]).strict
            if key is not None:
                self._by_size.setdefault(_size(key), []).append(index)
        self._indexed = len(self.data)
        key = _keys(self._before_record_request(request)).strict
        if key is None:
            return
        for index in self._by_size.get(_size(key), []):
            if _keys(self.data[index][0]).strict == key:
                yield index, self.data[index][1]

    @property
    def write_protected(self) -> bool:
        """vcrpy's rule, and under ``stop_on_drift`` a drifted replay records nothing more."""
        return bool(super().write_protected) or (self.stop_on_drift and self.drift is not None)

    def can_play_response_for(self, request: Request) -> bool:
        playable = bool(super().can_play_response_for(request))
        replaying = self.write_protected or (self.stop_on_drift and self._loaded > 0)
        if not playable and replaying and self.drift is None:
            self.drift = self._explain(_keys(self._before_record_request(request)))
        self.requests_made += 1
        return playable

    def _explain(self, new: MatchKeys) -> str:
        played = self._played(new)
        if played is not None:
            self.unreadable = True
            return unreadable_message(
                cassette=str(self._path),
                response_index=played,
                response=self.data[played][1],
                command=self.rerecord_command,
            )
        index = self.requests_made
        recorded = self.data[index][0] if index < len(self.data) else None
        return drift_message(
            cassette=str(self._path),
            request_index=index,
            new_tree=new.redacted.tree,
            recorded_tree=_keys(recorded).redacted.tree if recorded else None,
            recorded=len(self.data),
            command=self.rerecord_command,
        )

    def _played(self, new: MatchKeys) -> int | None:
        """The index of an already played interaction whose request equals ``new``."""
        key = new.strict if self.strict else new.lenient
        if key is None:
            return None
        for index, count in self.play_counts.items():
            old = _keys(self.data[index][0])
            if count and (old.strict if self.strict else old.lenient) == key:
                return index
        return None

    @property
    def recorded_modality(self) -> str | None:
        """The modality of the recording (from its first request), ``None`` if empty."""
        return request_modality(_keys(self.data[0][0]).redacted) if self.data else None


def _before_record_request(request: Request) -> Request:
    if getattr(request, "emrd_keys", None) is not None:
        return request  # read back from the cassette (already canonical) or redacted before
    # vcrpy asks three or four times per request (can it play, is it in, play, record):
    # the redacted copy is kept on the request, so each request is redacted once.
    redacted: Request | None = request.__dict__.get("emrd_redacted")
    if redacted is None:
        # A shallow copy suffices: redaction assigns new attributes and never mutates shared
        # ones (vcrpy's own configuration deep-copies the request, frames included, every call).
        redacted = request.emrd_redacted = redact_request(copy.copy(request))  # type: ignore[attr-defined]
    return redacted


def _before_record_response(response: dict[str, Any]) -> dict[str, Any] | None:
    # decode_compressed_response: store bodies decoded, whatever the server compressed
    # (vcrpy's decoder deep-copies the response first: only worth it when there is work).
    if any(name.lower() == "content-encoding" for name in response["headers"]):
        response = filters.decode_response(response)
    return keep_response(response)


@contextmanager
def episode_cassette(
    path: Path,
    *,
    protocol: str,
    record_mode: str,
    matching: str,
    rerecord_command: str,
    root: Path | None = None,
) -> Iterator[EpisodeCassette]:
    """Patch httpx with the episode's cassette for the duration of the block.

    vcrpy settings: ``allow_playback_repeats`` off, compressed responses stored decoded,
    ``record_on_exception`` off (raise inside the block to discard a failed episode), and
    in ``all`` mode the file is rebuilt from scratch. Inside :func:`~._routing.routing`
    (concurrent episodes) the cassette is bound to this thread instead of patching httpx.
    ``root`` is the cassette folder (see :class:`~._persister.EpisodePersister`).
    """
    frame_drift: set[tuple[Any, Any]] = set()
    settings: dict[str, Any] = dict(
        path=str(path),
        persister=EpisodePersister(
            protocol=protocol,
            fresh=record_mode == "all",
            rerecord_command=rerecord_command,
            root=root,
        ),
        record_mode=RecordMode(record_mode),
        match_on=(make_matcher(matching, frame_drift),),
        before_record_request=_before_record_request,
        before_record_response=_before_record_response,
        allow_playback_repeats=False,
        drop_unused_requests=record_mode == "all",
        skip_patchers=_routing.ABSENT_PATCHERS,
    )
    if _routing.active():  # episodes run concurrently: one patch routes to each thread's
        opened = _routing.bound(EpisodeCassette.load(**settings))
    else:
        opened = EpisodeCassette.use(**settings, record_on_exception=False)
    with opened as cassette:
        cassette.frame_drift = frame_drift
        cassette.strict = matching == "strict"
        cassette.rerecord_command = rerecord_command
        cassette.stop_on_drift = record_mode == "new_episodes"
        yield cassette
