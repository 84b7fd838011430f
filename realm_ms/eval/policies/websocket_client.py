"""The transport both websocket policy clients share (``openpi.py``, ``roboarena.py``).

- ``parse_addresses``: ``HOST:PORT[,HOST:PORT...]`` parsed once, strictly, before any work (IPv6
  hosts in brackets, ports 1..65535, ``,`` between servers, no scheme); one ``ValueError`` naming
  the bad entry.
- ``Connection``: one websocket to one server (msgpack-numpy over websockets, the server's metadata
  first). Connecting is retried with exponential back-off for ``max_wait_s``: "unreachable" after
  that. Everything else fails the request at once, naming the server: a text frame (the server's
  traceback: its last line is reported), a reply that is not msgpack-numpy, no reply within
  ``reply_timeout_s``, metadata the protocol's check refuses. The connection is then closed and
  opened again on the next request.
- ``ServerPool``: ``connections`` websockets per server; ``run(n, work)`` serves n rows at once, each
  on a free connection (or the row's own one, ``pinned``), at most ``max_in_flight`` in flight,
  results in row order, with each request's wall time.
- ``ServerPolicy``: the ``Policy`` both clients are (replies validated where they arrive, chunks
  assembled in row order, failed rows kept still, per-row latency and server).
"""

from __future__ import annotations

import ipaddress
import re
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from realm_ms.eval.policies.openpi_wire import packb, unpackb
from realm_ms.eval.policies.policy import Policy, PolicyInput, PolicyOutput
from realm_ms.eval.policies.replies import ReplyError

ADDRESS_HELP = "HOST:PORT[,HOST:PORT...] (IPv6 hosts in brackets: [::1]:8000)"
_LABEL = r"[A-Za-z0-9_](?:[A-Za-z0-9_-]{0,61}[A-Za-z0-9_])?"  # "_": container service names
_HOSTNAME = re.compile(rf"{_LABEL}(?:\.{_LABEL})*")
_ALLOWED = re.compile(r"[A-Za-z0-9_.\-:\[\]]*")


@dataclass(frozen=True)
class ServerAddress:
    host: str
    port: int

    def __str__(self) -> str:
        return f"[{self.host}]:{self.port}" if ":" in self.host else f"{self.host}:{self.port}"

    @property
    def uri(self) -> str:
        return f"ws://{self}"


def parse_addresses(text, kind: str) -> list[ServerAddress]:
    """``HOST:PORT[,HOST:PORT...]`` -> addresses; ``ValueError`` naming the first bad entry."""
    if not isinstance(text, str) or not text.strip():
        raise ValueError(f"{kind} needs a server address: {kind}:{ADDRESS_HELP}")
    return [_parse_one(entry.strip(), kind, text) for entry in text.split(",")]


def _parse_one(entry: str, kind: str, text: str) -> ServerAddress:
    from realm_ms.validate import check_port

    def bad(why: str) -> ValueError:
        return ValueError(f"{kind}:{text}: bad server address {entry!r}: {why}; expected {ADDRESS_HELP}")

    if not entry:
        raise bad("an empty entry (a stray ',')")
    if "://" in entry:
        raise bad("no scheme (ws://, http://) goes in front: give HOST:PORT")
    if not _ALLOWED.fullmatch(entry):
        c = next(ch for ch in entry if not _ALLOWED.fullmatch(ch))
        raise bad(f"unexpected character {c!r} (separate servers with ',')")
    if entry.startswith("["):
        m = re.fullmatch(r"\[([^\]]*)\]:(.*)", entry)
        if not m:
            raise bad("an IPv6 host is [ADDRESS]:PORT")
        host, port = m.groups()
        try:
            ipaddress.IPv6Address(host)
        except ValueError:
            raise bad(f"{host!r} is not an IPv6 address") from None
    else:
        host, sep, port = entry.rpartition(":")
        if not sep:
            raise bad("no port")
        if not host:
            raise bad("no host")
        if ":" in host or "[" in host or "]" in host:
            raise bad("an IPv6 host goes in brackets, e.g. [::1]:8000")
        if re.fullmatch(r"[0-9.]+", host):
            try:
                ipaddress.IPv4Address(host)
            except ValueError:
                raise bad(f"{host!r} is not an IPv4 address") from None
        elif len(host) > 253 or not _HOSTNAME.fullmatch(host):
            raise bad(f"{host!r} is not a host name")
    if not re.fullmatch(r"[0-9]{1,6}", port):
        raise bad(f"the port {port!r} is not a number")
    return ServerAddress(host, check_port(int(port), f"{kind}:{entry}: port"))


class ServerUnreachable(ConnectionError):
    """Connecting kept failing for the whole wait."""


class Connection:
    """One websocket to one server (module docstring); ``check_metadata(meta, source) -> meta``
    validates the handshake."""

    def __init__(self, address: ServerAddress, kind: str, max_wait_s: float, reply_timeout_s: float,
                 check_metadata: Callable[[object, str], dict], api_key: str | None = None):
        self.address, self.kind, self.max_wait_s, self.reply_timeout_s = address, kind, max_wait_s, reply_timeout_s
        self.check_metadata, self.api_key = check_metadata, api_key
        self.uri = address.uri
        self.source = f"{kind} server {address}"
        self.ws = None
        self.metadata: dict | None = None

    def _open(self) -> None:
        from websockets.sync.client import connect

        headers = {"Authorization": f"Api-Key {self.api_key}"} if self.api_key else None
        self.ws = connect(self.uri, compression=None, max_size=None, additional_headers=headers, open_timeout=10)

    def _handshake(self) -> None:
        try:
            first = self.ws.recv(timeout=self.reply_timeout_s)
        except TimeoutError:
            raise ReplyError(f"{self.source}: accepted the connection but sent no metadata within {self.reply_timeout_s:g} s "
                             f"(is it a {self.kind} policy server?)") from None
        except Exception as e:  # noqa: BLE001  closed before its first frame
            raise ReplyError(f"{self.source}: closed the connection before sending its metadata ({type(e).__name__}: {e})") from None
        self.metadata = self.check_metadata(self._decode(first, "metadata"), self.source)

    def _decode(self, data, what: str):
        if isinstance(data, str):  # a text frame: the server's traceback
            lines = data.strip().splitlines()
            raise ReplyError(f"{self.source} error: {lines[-1] if lines else '(empty text frame)'}")
        try:
            return unpackb(data)
        except Exception as e:  # noqa: BLE001  (msgpack raises several unrelated types)
            raise ReplyError(f"{self.source}: its {what} is not msgpack-numpy ({type(e).__name__}: {e}; {len(data)} bytes)") from None

    def connect(self) -> None:
        """Open the connection and read the metadata, retrying unreachable servers for ``max_wait_s``."""
        deadline = time.monotonic() + self.max_wait_s
        delay, last = 0.25, None
        while self.ws is None:
            try:
                self._open()
            except ReplyError:
                raise
            except Exception as e:  # noqa: BLE001  refused, reset, DNS, handshake (websockets' own types)
                last = e
                self.close()
                if time.monotonic() + delay > deadline:
                    raise ServerUnreachable(f"{self.source} unreachable for {self.max_wait_s:g} s ({type(last).__name__}: {last})") from None
                time.sleep(delay)
                delay = min(delay * 2, 5.0)
                continue
            try:
                self._handshake()
            except BaseException:
                self.close()
                raise

    def close(self) -> None:
        if self.ws is not None:
            try:
                self.ws.close()
            except Exception:  # noqa: BLE001
                pass
        self.ws = None

    def exchange(self, message: dict, text_ok: Callable[[str], bool] | None = None):
        """Send one message, return the decoded reply (a text frame only where ``text_ok`` accepts
        it). A connection that dropped since the last request is reopened (with the retries)."""
        for attempt in (0, 1):
            self.connect()
            try:
                self.ws.send(packb(message))
                reply = self.ws.recv(timeout=self.reply_timeout_s)
            except TimeoutError:
                self.close()
                raise ReplyError(f"{self.source}: no reply within {self.reply_timeout_s:g} s") from None
            except Exception as e:  # noqa: BLE001  closed between requests: reopen once
                self.close()
                if attempt:
                    raise ServerUnreachable(f"{self.source} closed the connection ({type(e).__name__}: {e})") from None
                continue
            if isinstance(reply, str) and text_ok is not None and text_ok(reply):
                return reply
            try:
                return self._decode(reply, "reply")
            except ReplyError:
                self.close()
                raise
        raise AssertionError("not reached")  # pragma: no cover


class ServerPool:
    """``connections`` websockets per server, every row of a round in flight at once (module docstring)."""

    def __init__(self, addresses: list[ServerAddress], kind: str, max_wait_s: float, check_metadata, connections: int = 1,
                 max_in_flight: int | None = None, reply_timeout_s: float | None = None, api_key: str | None = None):
        from realm_ms.validate import check_positive

        check_positive(max_wait_s, "--openpi-wait", "s")  # every websocket server's wait; a NaN deadline never passes
        if connections < 1:
            raise ValueError(f"{kind} connections per server must be >= 1, got {connections}")
        reply_timeout_s = max(max_wait_s, 60.0) if reply_timeout_s is None else check_positive(reply_timeout_s, "reply timeout", "s")
        # round-robin over servers, so a partial pool still spreads over every server
        self.conns = [Connection(a, kind, max_wait_s, reply_timeout_s, check_metadata, api_key) for _ in range(connections) for a in addresses]
        self.max_in_flight = max(1, min(int(max_in_flight or len(self.conns)), len(self.conns)))
        self._pool = None

    @property
    def metadata(self) -> dict | None:
        return next((c.metadata for c in self.conns if c.metadata is not None), None)

    def run(self, n: int, work: Callable[[Connection, int], object], pinned: list[int] | None = None) -> list[tuple[object, str | None, float, str]]:
        """``work(conn, i)`` for rows 0..n-1 concurrently; per row (result | None, error | None,
        wall time s, server). ``ReplyError`` / ``ConnectionError`` become that row's error."""

        def serve(conn: Connection, i: int):
            t = time.perf_counter()
            try:
                return work(conn, i), None, time.perf_counter() - t, str(conn.address)
            except (ConnectionError, RuntimeError) as e:
                return None, str(e), time.perf_counter() - t, str(conn.address)
            except Exception as e:  # noqa: BLE001  anything else a server provokes fails its row, not the round
                conn.close()
                return None, f"{conn.source}: {type(e).__name__}: {e}", time.perf_counter() - t, str(conn.address)

        if n == 0:
            return []
        if pinned is None and (self.max_in_flight == 1 or n == 1):
            return [serve(self.conns[0], i) for i in range(n)]
        import queue
        from concurrent.futures import ThreadPoolExecutor

        if self._pool is None:
            self._pool = ThreadPoolExecutor(self.max_in_flight, thread_name_prefix="policy-client")
        if pinned is None:
            idle: queue.SimpleQueue = queue.SimpleQueue()
            for c in self.conns[: self.max_in_flight]:
                idle.put(c)

            def one(i: int):
                conn = idle.get()  # a free connection: bounds the requests in flight
                try:
                    return serve(conn, i)
                finally:
                    idle.put(conn)
        else:
            locks = [threading.Lock() for _ in self.conns]

            def one(i: int):
                k = pinned[i] % len(self.conns)
                with locks[k]:  # one request at a time per connection; the executor bounds the rest
                    return serve(self.conns[k], i)

        return list(self._pool.map(one, range(n)))

    def close(self) -> None:
        for c in self.conns:
            c.close()
        if self._pool is not None:
            self._pool.shutdown(wait=False)
            self._pool = None


class ServerPolicy(Policy):
    """What the websocket policies share: the pool, each reply validated where it arrives, the
    round's chunks assembled in row order (a failed row keeps still, in the env's action space;
    shorter chunks hold their last action), each row's request wall time and server.

    Subclasses set ``name`` and implement ``request(batch, i) -> dict``, ``actions(reply, source)``
    (the reply's raw actions), ``env_action_space()`` and ``check_metadata(meta, source)``."""

    text_ok: Callable[[str], bool] | None = None

    def __init__(self, address: str, max_wait_s: float = 30.0, connections: int = 1, max_in_flight: int | None = None,
                 reply_timeout_s: float | None = None, api_key: str | None = None):
        self.addresses = parse_addresses(address, self.name)
        self.address = ",".join(str(a) for a in self.addresses)
        self.max_wait_s, self.connections = max_wait_s, connections
        self.pool = ServerPool(self.addresses, self.name, max_wait_s, self.check_metadata, connections, max_in_flight,
                               reply_timeout_s, api_key)
        self.conns = self.pool.conns
        self.max_in_flight = self.pool.max_in_flight
        self._space_cache = None

    @property
    def uri(self) -> str:
        return self.conns[0].uri

    @property
    def metadata(self) -> dict:
        return self.pool.metadata or {}

    def spec(self) -> str:
        return f"{self.name}:{self.address}"

    def check_metadata(self, meta, source: str) -> dict:
        from realm_ms.eval.policies.replies import check_metadata

        return check_metadata(meta, source)

    def _space(self):
        """(DroidActionSpace, DroidIK | None) of the replies: fixed once known."""
        from realm_ms.agents.droid_action_spaces import DroidIK, make_action_space

        if self._space_cache is not None:
            return self._space_cache
        kw = self.env_action_space()
        space = make_action_space(kw.get("action_space", "joint_position"), kw.get("gripper_action_space"))
        ik = DroidIK() if space.action_space.startswith("cartesian") else None
        if self.space_known():
            self._space_cache = (space, ik)
        return space, ik

    def space_known(self) -> bool:
        return self.pool.metadata is not None

    def pinned(self, batch: PolicyInput) -> list[int] | None:
        """The connection each row must use (None: any free one)."""
        return None

    def infer(self, obs: dict) -> dict:
        """One request on the first connection (sequential use, tests)."""
        return self.conns[0].exchange(obs)

    def act(self, batch: PolicyInput) -> PolicyOutput:
        """Every row's request in flight at once over the pool; results in row order; a row whose
        server stays down, errs or answers wrongly gets an error naming the server, the others are served."""
        from realm_ms.eval.policies.replies import check_chunk

        try:
            space, ik = self._space()
        except ReplyError as e:  # the first server's metadata is bad: every row fails, naming it
            return PolicyOutput(np.repeat(batch.state[:, None, :], 1, axis=1), [str(e)] * len(batch))

        def work(conn: Connection, i: int):
            reply = conn.exchange(self.request(batch, i), self.text_ok)
            return check_chunk(self.actions(reply, conn.source), space, conn.source)

        results = self.pool.run(len(batch), work, self.pinned(batch))
        chunks = [self.postprocess(c, space) if c is not None else None for c, _, _, _ in results]
        errors = [e for _, e, _, _ in results]
        t = max((c.shape[0] for c in chunks if c is not None), default=1)
        hold = space.hold(batch.state[:, :7], batch.state[:, 7], ik).astype(np.float32)  # failed rows keep still
        out = np.repeat(hold[:, None, :], t, axis=1)
        for i, c in enumerate(chunks):
            if c is not None:
                out[i, : len(c)] = c
                out[i, len(c):] = c[-1]  # shorter chunks: hold their last action
        return PolicyOutput(out, errors if any(errors) else None, latency_s=[r[2] for r in results], servers=[r[3] for r in results])

    def postprocess(self, chunk: np.ndarray, space) -> np.ndarray:
        """A valid chunk as the env gets it: a ``position`` gripper clipped to [0, 1]."""
        if space.gripper == "position":
            chunk[:, -1] = np.clip(chunk[:, -1], 0.0, 1.0)
        return chunk

    def close(self) -> None:
        self.pool.close()
