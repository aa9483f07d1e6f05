"""One episode's vcrpy cassette: redaction, matching, record modes and drift detection.

Every episode, alone or concurrent (``--emrd-concurrency``, threads of one process), goes
through :func:`_routing`: vcrpy's process-wide patches, bound once to a router that hands each
call to the calling thread's cassette."""

from __future__ import annotations

import contextlib
import copy
import functools
import threading
import time
from collections.abc import Callable, Iterator
from contextvars import ContextVar
from pathlib import Path
from typing import Any, Final
from urllib.parse import urlparse

from vcr import filters
from vcr.cassette import Cassette
from vcr.patch import CassettePatcherBuilder
from vcr.record_mode import RecordMode
from vcr.request import Request

from pytest_emrd import _wire
from pytest_emrd._scrub import scrub_bytes, scrub_uri
from pytest_emrd.cassette._paths import drift_message, request_modality, unreadable_message
from pytest_emrd.cassette._persister import EpisodePersister, UnsavedCassette
from pytest_emrd.cassette._redact import MatchKeys, match_keys, redact_body, scrub_headers
from pytest_emrd.errors import CassetteError

#: Response headers kept in a cassette (the body is stored decoded, so no Content-Encoding).
KEPT_RESPONSE_HEADERS: Final = frozenset({"content-type"})
_current: ContextVar[Cassette | None] = ContextVar("emrd_cassette", default=None)
_lock = threading.Lock()
_patches = contextlib.ExitStack()
_users = 0


def clear_caches() -> None:
    """Forget every cached message encoding and redaction, as at the start of a run
    (cold benchmarks, tests).

    :returns: Nothing; the caches are empty afterwards.
    """
    _wire.clear()


def _keys(request: Request) -> MatchKeys:
    """The keys ``request`` is matched on (of its canonical body and of its path as a cassette
    stores it), computed once and kept on it."""
    keys = getattr(request, "emrd_keys", None)
    if keys is None:
        path = urlparse(scrub_uri(request.uri)).path
        keys = match_keys(request.method, path, redact_body(request.body))
        request.emrd_keys = keys  # type: ignore[attr-defined]
    return keys


def _key(request: Request, strict: bool) -> Any:
    keys = _keys(request)
    return keys.strict if strict else keys.lenient


def _slot(key: Any) -> Any:
    """Where :class:`EpisodeCassette`'s index files a key: a strict ``(head, body)`` by its
    head and body length, a lenient key (a short digest) as it is."""
    return (key[0], len(key[1])) if isinstance(key, tuple) else key


def _matcher(strict: bool) -> Callable[[Request, Request], bool]:
    """vcrpy's one matcher for a cassette: key equality (unparseable never matches). Not a
    method: a cassette holding its own bound method would live until the garbage collector
    finds the cycle, its recording (a few MB) with it."""

    def emrd_body(new: Request, recorded: Request) -> bool:
        key = _key(new, strict)
        return key is not None and key == _key(recorded, strict)

    return emrd_body


class EpisodeCassette(Cassette):
    """A vcrpy cassette that remembers why a replay failed (see :mod:`._paths`): the first request
    that cannot be played while write-protected is explained as an unreadable recorded response
    when it repeats one already played (a retry), else as drift against the recorded request
    at the same position."""

    def __init__(
        self, *args: Any, matching: str = "strict", rerecord_command: str = "", **kwargs: Any
    ) -> None:
        self.frame_drift: set[tuple[Any, Any]] = set()
        self.strict = matching == "strict"
        super().__init__(*args, match_on=(_matcher(self.strict),), **kwargs)
        self.requests_made = 0
        self.drift: str | None = None
        self.rerecord_command = rerecord_command
        self.unreadable = False
        """The failure is a recorded response the client could not read (not drift)."""
        self.stop_on_drift = self.record_mode == RecordMode.NEW_EPISODES
        """A request the recording does not hold stops the episode (to be recorded again
        whole)."""
        self._loading = False
        self._loaded = 0
        self._asked = 0.0
        self._index: dict[str, list[int]] | None = None

    def key(self, request: Request) -> Any:
        """The key ``request`` is matched by: strict or lenient (``None``: unparseable)."""
        return _key(request, self.strict)

    def _responses(self, request: Request) -> Iterator[tuple[int, dict[str, Any]]]:
        """vcrpy's lookup of the interactions :func:`_matcher` matches, in order, from an index
        (vcrpy runs the matcher on every interaction, three times per request) that files a
        strict key by its head and body length: hashing a body of tens of KB costs more than
        comparing it. A lenient match whose frames differ adds its pair of strict keys to
        :attr:`frame_drift`."""
        key = self.key(self._before_record_request(request))
        if self._index is None:
            self._index = {}
            for index, (stored, _) in enumerate(self.data):
                self._index.setdefault(_slot(self.key(stored)), []).append(index)
        for index in self._index.get(_slot(key), []) if key is not None else []:
            stored, response = self.data[index]
            if self.key(stored) != key:
                continue
            if (
                not self.strict
                and (pair := (_keys(request).strict, _keys(stored).strict))[0] != pair[1]
            ):
                self.frame_drift.add(pair)
            yield index, response

    def _load(self) -> None:
        self._loading = True
        try:
            super()._load()
        finally:
            self._loading = False
            self._loaded = len(self.data)

    def append(self, request: Request, response: dict[str, Any]) -> None:
        """vcrpy's ``append``, keeping only the replies that counted: a request recorded again right
        after itself is a retry (the client could not read the reply), so the new reply replaces
        the unreadable one and a replay gets the good reply first. An interaction read back from
        our own file is not deep-copied (nothing else holds it). A live reply keeps how long it
        took in :data:`LATENCY` (seconds since the request was looked up)."""
        if not self._loading:
            response = copy.deepcopy(response)
            response[LATENCY] = round(time.perf_counter() - self._asked, 3)
        read_back = self._loading and getattr(request, "emrd_keys", None) is not None
        kept = (
            (request if read_back else _redacted(request)),
            self._before_record_response(response),
        )
        if not kept[0] or kept[1] is None:
            return
        if not self._loading and self._retried(kept[0]):
            self.data[-1] = kept
        else:
            self.data.append(kept)
        self.dirty, self._index = True, None

    def _retried(self, request: Request) -> bool:
        """Whether ``request`` repeats the last interaction recorded live (not read back)."""
        if len(self.data) <= self._loaded:
            return False
        key = _keys(request).strict
        return key is not None and key == _keys(self.data[-1][0]).strict

    @property
    def write_protected(self) -> bool:
        """vcrpy's rule, and under ``stop_on_drift`` a drifted replay records nothing more."""
        return bool(super().write_protected) or (self.stop_on_drift and self.drift is not None)

    def can_play_response_for(self, request: Request) -> bool:
        playable = bool(super().can_play_response_for(request))
        replaying = self.write_protected or (self.stop_on_drift and self._loaded > 0)
        if not playable and replaying and self.drift is None:
            self.drift = self._explain(self._before_record_request(request))
        self.requests_made += 1
        self._asked = time.perf_counter()
        return playable

    def _explain(self, new: Request) -> str:
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
            new_tree=_keys(new).redacted.tree,
            recorded_tree=_keys(recorded).redacted.tree if recorded else None,
            recorded=len(self.data),
            command=self.rerecord_command,
        )

    def _played(self, new: Request) -> int | None:
        """The index of an already played interaction whose request equals ``new``."""
        key = self.key(new)
        played = [i for i, n in self.play_counts.items() if n and self.key(self.data[i][0]) == key]
        return played[0] if played and key is not None else None

    @property
    def unsaved(self) -> UnsavedCassette | None:
        """The recording, once the block has closed, when its file could not be written."""
        persister = self._persister
        return persister.unsaved if isinstance(persister, EpisodePersister) else None

    @property
    def recorded_modality(self) -> str | None:
        """The modality of the recording (from its first request), ``None`` if empty."""
        return request_modality(_keys(self.data[0][0]).redacted) if self.data else None


def _before_record_request(request: Request) -> Request:
    """vcrpy ``before_record_request``, asked three or four times per request: the request itself,
    keyed (:func:`_keys`); the copy a cassette stores is made only when it records one
    (:func:`_redacted`)."""
    _keys(request)
    return request


def _redacted(request: Request) -> Request:
    """The copy of ``request`` a cassette stores: canonical body, secrets dropped (a shallow
    copy: redaction assigns new attributes, never mutates shared ones)."""
    redacted = copy.copy(request)
    uri = scrub_uri(request.uri)
    if uri != request.uri:  # vcrpy parses the URI again on every assignment
        redacted.uri = uri
    redacted.body = _keys(request).redacted.body
    redacted.headers = scrub_headers(request.headers)
    return redacted


#: The optional field of a recorded response holding the seconds the live request took.
LATENCY: Final = "emrd_latency_s"


def _before_record_response(response: dict[str, Any]) -> dict[str, Any] | None:
    """vcrpy ``before_record_response``: drop non-2xx responses and volatile headers, store
    the body decoded and without configured key values."""
    if any(name.lower() == "content-encoding" for name in response["headers"]):
        response = filters.decode_response(response)  # a copy, decoded
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


class _Router:
    """Stands in for a cassette in vcrpy's patches; forwards to the thread's cassette."""

    custom_patches = ()
    skip_patchers = ()

    def __getattr__(self, name: str) -> Any:
        cassette = _current.get()
        if cassette is None:
            if name == "_path":  # vcrpy names its patched classes after it, before any binding
                return "<emrd: the cassette of the calling thread>"
            raise CassetteError(
                "an HTTP request was made outside any episode's thread while an episode runs; "
                "make model requests only inside an episode, on the thread that runs it."
            )
        return getattr(cassette, name)

    def __len__(self) -> int:  # vcrpy's CannotOverwriteExistingCassetteException counts them
        return len(self.__getattr__("data"))


@functools.cache
def _patchers() -> tuple[Any, ...]:
    """vcrpy's patches of the HTTP libraries, bound to the router: built once (building tries
    to import every library vcrpy knows), entered and left again with each first block."""
    return tuple(CassettePatcherBuilder(_Router()).build())


@contextlib.contextmanager
def _routing() -> Iterator[None]:
    """Keep vcrpy's patches on the HTTP libraries while any block is open (re-entrant, from any
    thread, closed in any order), each request handed to its thread's cassette.

    Every episode goes through here: two cassettes patching httpx themselves would restore
    each other's originals when their blocks overlap in time, and the later one would record
    nothing."""
    global _users
    with _lock:
        if _users == 0:
            for patcher in _patchers():
                _patches.enter_context(patcher)
        _users += 1
    try:
        yield
    finally:
        with _lock:
            _users -= 1
            if _users == 0:
                _patches.close()


@contextlib.contextmanager
def episode_cassette(
    path: Path,
    *,
    protocol: str,
    record_mode: str,
    matching: str,
    rerecord_command: str,
    root: Path | None = None,
    keep_unsaved: bool = False,
) -> Iterator[EpisodeCassette]:
    """Route httpx to the episode's cassette for the block (raise inside it to discard a
    failed episode); ``root`` and ``keep_unsaved``: :class:`~._persister.EpisodePersister`.

    :param path: The episode's cassette file.
    :param protocol: The protocol version the cassette must carry.
    :param record_mode: ``none``, ``once``, ``new_episodes`` or ``all``.
    :param matching: ``strict`` or ``lenient`` request matching.
    :param rerecord_command: The command a drift message recommends.
    :param root: The folder ``path`` must lie in; None for ``path``'s own.
    :param keep_unsaved: Hand an unwritable recording back instead of raising.
    :returns: A context manager yielding the :class:`EpisodeCassette`.
    """
    cassette = EpisodeCassette.load(
        path=str(path),
        persister=EpisodePersister(
            protocol=protocol,
            fresh=record_mode == "all",
            rerecord_command=rerecord_command,
            root=root,
            keep_unsaved=keep_unsaved,
        ),
        record_mode=RecordMode(record_mode),
        matching=matching,
        rerecord_command=rerecord_command,
        before_record_request=_before_record_request,
        before_record_response=_before_record_response,
        allow_playback_repeats=False,
        drop_unused_requests=record_mode == "all",
    )
    with _routing():
        token = _current.set(cassette)  # this thread's requests go to this cassette
        try:
            yield cassette
        finally:
            _current.reset(token)
    cassette._save()  # only when the block succeeded, as vcrpy's record_on_exception=False
