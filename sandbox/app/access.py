"""Who may talk to the sandbox's server, decided from each request alone.

The rules follow Jupyter's server:

- **Host.** A request whose ``Host`` header names a host the server does not
  answer to is refused (a DNS-rebinding page reaches 127.0.0.1 under its own
  name). The server answers to the loopback names, to the address it listens
  on, and, when it listens on every interface (``--host 0.0.0.0``), to any IP
  address (a rebinding attack needs a name, never an address) and to this
  machine's own names. ``--allow-host`` adds names (``*``: any, behind a proxy).
- **Origin.** A websocket whose ``Origin`` is not the page's own (scheme-less
  ``host:port`` equal to the ``Host`` it asked) or one given with
  ``--allow-origin`` is refused: another site's page cannot drive the
  sandbox. A client that sends no ``Origin`` is not a browser page, so the
  cross-site rule does not apply to it.
- **Token.** Served beyond this machine, control needs the secret token that
  start-up prints in the URL (``?token=...``). The page's first request
  carries it; the answer stores it in a cookie (``HttpOnly``,
  ``SameSite=Strict``) and drops it from the address bar, so the websocket,
  which viser opens without the query, presents the cookie. Scripts may send
  ``Authorization: token ...`` instead. Without the token a page may still
  *watch* (``viewers="watch"``, the default), or is refused (``"none"``).
- **Light programs** run Python files on the server: only a controlling
  connection from this machine's own loopback address may load them, unless
  the server was started with ``--allow-programs``. It is decided from the
  connection's address, not from the address the server listens on.

Nothing here knows viser: :mod:`sandbox.app.gate` applies a :class:`Decision`
to its handshake.
"""

from __future__ import annotations

import hmac
import ipaddress
import secrets
import socket
from dataclasses import dataclass, field
from http.cookies import CookieError, SimpleCookie
from typing import Iterable, Mapping
from urllib.parse import parse_qs, urlsplit

LOOPBACK_NAMES = frozenset({"localhost"})
WILDCARD_HOSTS = frozenset({"0.0.0.0", "::", ""})
CONTROL, WATCH = "control", "watch"


def is_loopback_host(host: str) -> bool:
    """``localhost`` or a loopback address (127.0.0.0/8, ::1)."""
    if host.lower() in LOOPBACK_NAMES:
        return True
    address = _ip(host)
    return address is not None and address.is_loopback


def is_shared(listen_host: str) -> bool:
    """Whether a server listening on ``listen_host`` can be reached from other machines."""
    return not is_loopback_host(listen_host)


def new_token() -> str:
    return secrets.token_urlsafe(24)


@dataclass(frozen=True)
class Grant:
    """What one websocket connection may do: ``role`` is "control" or "watch"."""

    role: str
    programs: bool = False  # may load light programs (Python files on the server)
    address: str = ""

    @property
    def controls(self) -> bool:
        return self.role == CONTROL


@dataclass(frozen=True)
class Decision:
    """The answer to one request: refused (``status`` and ``reason``), or a grant."""

    grant: Grant | None = None
    status: int = 200
    reason: str = ""
    #: The token the request brought in its query: answer with a cookie that keeps it.
    store_token: bool = False

    @property
    def refused(self) -> bool:
        return self.grant is None


@dataclass
class Access:
    """The server's rules (see the module docstring). ``port`` is set once the server listens."""

    listen_host: str = "127.0.0.1"
    port: int = 0
    token: str | None = None
    viewers: str = WATCH  # what a page without the token may do on a shared server: "watch" or "none"
    allow_programs: bool = False  # any controlling connection may load light programs
    allowed_hosts: frozenset = field(default_factory=frozenset)
    allowed_origins: frozenset = field(default_factory=frozenset)

    @classmethod
    def for_server(cls, listen_host: str, *, token: str | None = None, viewers: str = WATCH,
                   allow_programs: bool = False, allow_hosts: Iterable[str] = (),
                   allow_origins: Iterable[str] = ()) -> "Access":
        """The rules for a server on ``listen_host``: shared beyond this machine, it needs a token
        (a new one unless given); on loopback, only if one is given."""
        if viewers not in (WATCH, "none"):
            raise ValueError(f"viewers must be 'watch' or 'none', not {viewers!r}")
        origins = {o: _origin_key(o) for o in allow_origins}
        bad = [o for o, key in origins.items() if key is None]
        if bad:
            raise ValueError(f"--allow-origin {bad[0]!r} is not an origin such as https://example.org:8443")
        if token is None and is_shared(listen_host):
            token = new_token()
        return cls(listen_host=listen_host, token=token or None, viewers=viewers, allow_programs=allow_programs,
                   allowed_hosts=frozenset(h.lower() for h in allow_hosts),
                   allowed_origins=frozenset(origins.values()))

    @property
    def cookie_name(self) -> str:
        return f"phototaxis-token-{self.port}"  # cookies are per host, not per port

    # ----------------------------------------------------------- decisions
    def decide(self, headers: Mapping[str, str], path: str, peer: str, *, websocket: bool) -> Decision:
        """Decide a request from its headers, path (with query) and the peer's address."""
        host = headers.get("Host")
        if not host or not self.host_allowed(_hostname(host)):
            return Decision(status=403, reason=f"this server does not answer to the host {host!r}; "
                                               f"start it with --allow-host to add a name")
        origin = headers.get("Origin")
        if websocket and origin is not None and not self.origin_allowed(origin, host):
            return Decision(status=403, reason=f"pages from {origin!r} may not connect to this sandbox")
        given = self._token_in(headers, path)
        authorised = self.token is None or (given is not None and hmac.compare_digest(given, self.token))
        if not authorised and self.viewers == "none":
            return Decision(status=403, reason="this sandbox needs the link with its token (?token=...)")
        role = CONTROL if authorised else WATCH
        programs = role == CONTROL and (self.allow_programs or is_loopback_host(peer))
        store = authorised and self.token is not None and _query_token(path) is not None
        return Decision(grant=Grant(role, programs, peer), store_token=store)

    def host_allowed(self, hostname: str) -> bool:
        hostname = hostname.lower().rstrip(".")
        if "*" in self.allowed_hosts or hostname in self.allowed_hosts or is_loopback_host(hostname):
            return True
        if self.listen_host.lower() not in WILDCARD_HOSTS:
            return hostname == self.listen_host.lower()
        return _ip(hostname) is not None or hostname in _own_names()

    def origin_allowed(self, origin: str, host: str) -> bool:
        key = _origin_key(origin)
        return key is not None and (key in self.allowed_origins or key.split("://", 1)[1] == _host_key(host))

    def _token_in(self, headers: Mapping[str, str], path: str) -> str | None:
        authorization = headers.get("Authorization", "")
        if authorization.lower().startswith("token "):
            return authorization[6:].strip()
        cookies = SimpleCookie()
        try:
            cookies.load(headers.get("Cookie", ""))
        except CookieError:
            pass
        if self.cookie_name in cookies:
            return cookies[self.cookie_name].value
        return _query_token(path)

    def set_cookie_header(self) -> str:
        return f"{self.cookie_name}={self.token}; Path=/; HttpOnly; SameSite=Strict"

    def url(self, shown_host: str) -> str:
        query = f"?token={self.token}" if self.token else ""
        return f"http://{_bracketed(shown_host)}:{self.port}/{query}"


# ------------------------------------------------------------------ parsing
def _ip(host: str) -> ipaddress.IPv4Address | ipaddress.IPv6Address | None:
    try:
        return ipaddress.ip_address(host.strip("[]").split("%")[0])
    except ValueError:
        return None


def _hostname(host_header: str) -> str:
    """The name in a ``Host`` header, without its port (``[::1]:80`` -> ``::1``)."""
    host_header = host_header.strip()
    if host_header.startswith("["):
        return host_header[1:].split("]", 1)[0]
    if host_header.count(":") > 1:  # a bare IPv6 address
        return host_header
    return host_header.rsplit(":", 1)[0] if ":" in host_header else host_header


def _host_key(host_header: str) -> str:
    """``host:port`` of a Host header, lower case, port 80 spelled out."""
    name = _hostname(host_header).lower()
    port = host_header.strip().rsplit(":", 1)[1] if host_header.strip().rsplit("]", 1)[-1].count(":") == 1 else "80"
    return f"{_bracketed(name)}:{port}"


def _origin_key(origin: str) -> str | None:
    """``scheme://host:port`` of an Origin, lower case with the default port spelled out; None if malformed."""
    try:
        parts = urlsplit(origin.strip())
        port = parts.port
    except ValueError:
        return None
    if parts.scheme not in ("http", "https") or not parts.hostname:
        return None  # "null" (a sandboxed frame or a file://), or not a URL
    port = port or (443 if parts.scheme == "https" else 80)
    return f"{parts.scheme}://{_bracketed(parts.hostname.lower())}:{port}"


def _bracketed(host: str) -> str:
    return f"[{host}]" if ":" in host and not host.startswith("[") else host


def _query_token(path: str) -> str | None:
    values = parse_qs(urlsplit(path).query).get("token")
    return values[0] if values else None


def _own_names() -> frozenset:
    """This machine's names, as a browser on the network may ask for it."""
    names = {socket.gethostname().lower()}
    try:
        names.add(socket.getfqdn().lower())
    except OSError:
        pass
    return frozenset(n for n in names if n)
