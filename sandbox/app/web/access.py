"""Who may talk to the sandbox's server, decided from each request alone.
Pure decisions, taken on viser's event loop as each request arrives.

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
  cross-site rule does not apply to it. A request that repeats ``Host`` or
  ``Origin`` is refused whatever the values: which one to believe is not
  ours to guess (and websockets' headers refuse to pick one).
- **Token.** Served beyond this machine, control needs the secret token that
  start-up prints in the URL (``?token=...``). The page's first request
  carries it; the answer stores it in a cookie (``HttpOnly``,
  ``SameSite=Strict``) and sends the page on to the same path of ours without
  it (:func:`redirect_target`: never to another site), so the websocket,
  which viser opens without the query, presents the cookie. Scripts may send
  ``Authorization: token ...`` instead. A request is authorised when any token
  it presents (each header, cookie and query parameter) is the server's; one
  that presents a malformed token (not :func:`well_formed_token`, e.g.
  non-ASCII or empty), among any number of good ones, is refused with 403.
  Without the token a page may still *watch* (``viewers="watch"``, the
  default), or is refused (``"none"``).
- **Seats** (``serve --class``): a page that asks the students' link
  (:data:`JOIN_PATH`) is sent on to an address of its own, ``/seat/<identity>``
  (:data:`SEAT_PATH`), whose identity the server issues (``secrets.token_urlsafe``,
  :class:`Seats`' ``issue``) for the page's address. The page and its
  websocket (which viser opens at the page's path) present it; it is taken only
  when the server issued it for the same address (``Seats.check``); the grant
  is a seat's: its page acts on its own world only (the gate lets one page hold a
  seat at a time, the inbox looks up its controls in its own GUI alone). In a
  lesson no page watches the teacher's: a page without the token that asks
  ``/`` is sent to the students' link, and its websocket is refused.
- **Light programs** run Python files on the server: only a controlling page
  on this machine may load them (:meth:`Access.local_page`), unless the server
  was started with ``--allow-programs``. It is decided from the connection's
  address, not from the address the server listens on. A connection that
  carries a reverse proxy's headers is not this machine's page, unless the
  server was started with ``--trust-proxy``: then a connection from this
  machine (the proxy) that carries ``X-Forwarded-For`` is the page at that
  header's last address, the one the proxy added.

Nothing here knows viser: :mod:`sandbox.app.web.gate` applies a :class:`Decision`
to its handshake.
"""

from __future__ import annotations

import hmac
import ipaddress
import re
import secrets
import socket
from dataclasses import dataclass, field
from typing import Iterable, Mapping, Protocol
from urllib.parse import parse_qs, urlsplit

LOOPBACK_NAMES = frozenset({"localhost"})
WILDCARD_HOSTS = frozenset({"0.0.0.0", "::", ""})
CONTROL, WATCH, SEAT = "control", "watch", "seat"
#: The students' link (``serve --class``), and where each student's page lives: ``/seat/<identity>``.
JOIN_PATH = "/join"
SEAT_PATH = "/seat/"
#: A seat's identity as the server issues it (``secrets.token_urlsafe(24)``: 32 of these characters).
SEAT_PATTERN = re.compile(r"[A-Za-z0-9_-]{32}")
#: A token is a cookie's value: RFC 6265's cookie-octets (printable ASCII but for space, ", comma, ; and backslash).
TOKEN_PATTERN = re.compile(r"[\x21\x23-\x2B\x2D-\x3A\x3C-\x5B\x5D-\x7E]{1,256}")
#: Headers a reverse proxy adds: a request that carries one came through a proxy (or says so).
PROXY_HEADERS = ("Forwarded", "X-Forwarded-For", "X-Real-IP")
#: Headers a request may carry once: two Hosts or two Origins are refused, whatever they say.
SINGLE_HEADERS = ("Host", "Origin")
#: A path of ours to send a page on to: segments of unreserved characters, one "/" each (never "//").
OWN_PATH = re.compile(r"/(?:[A-Za-z0-9._~-]+/)*[A-Za-z0-9._~-]*")


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


def well_formed_token(token: str) -> bool:
    """Whether ``token`` can be a token at all (:data:`TOKEN_PATTERN`): anything else a request presents is
    refused, whatever the server's token is."""
    return TOKEN_PATTERN.fullmatch(token) is not None


def redirect_target(path: str) -> str:
    """Where to send a page that brought the token in its query: the same path without the query if it
    is a plain path of ours (:data:`OWN_PATH`), else ``/``. Never another site (``//evil.example/``,
    ``/\\evil.example``, ``https://evil.example/`` all go to ``/``)."""
    plain = path.split("?", 1)[0].split("#", 1)[0]
    return plain if OWN_PATH.fullmatch(plain) else "/"


def same_machine(address: str, server_address: str = "") -> bool:
    """Whether a connection from ``address`` comes from this machine: a loopback address, or the very address
    it reached the server at (a page on this machine that asked for this machine's network name)."""
    ip = _client_ip(address)
    return ip is not None and (ip.is_loopback or ip == _client_ip(server_address))


def address_group(address: str) -> str:
    """The pages that count as one address for a per-address limit: every loopback address is one (this
    machine), an IPv6 address counts by its /64 (what one home or host is given), an IPv4 address alone."""
    ip = _client_ip(address)
    if ip is None:
        return address
    if ip.is_loopback:
        return "loopback"
    if ip.version == 6:
        return str(ipaddress.ip_network(f"{ip}/64", strict=False))
    return str(ip)


@dataclass(frozen=True)
class Grant:
    """What one websocket connection may do: ``role`` is "control", "watch" or "seat" (a student's page,
    which acts on the world of its ``seat`` alone)."""

    role: str
    programs: bool = False  # may load light programs (Python files on the server)
    address: str = ""  # the page's address: the peer's, or behind a trusted proxy the one it forwarded
    seat: str = ""  # a seat's identity (role "seat")

    @property
    def controls(self) -> bool:
        """Controls the shared world (the token's page)."""
        return self.role == CONTROL

    @property
    def acts(self) -> bool:
        """May send controls at all: the token's page, or a seat's on its own world."""
        return self.role in (CONTROL, SEAT)


class Seats(Protocol):
    """The class's seats as the gate asks them (``serve --class``; kept by sandbox.app.lesson.seats):
    called on viser's event loop."""

    def issue(self, address: str) -> str | None:
        """A new seat's identity for a page at ``address``, or None when the class is full."""

    def check(self, identity: str, address: str) -> str:
        """Why a page at ``address`` may not take the seat ``identity`` ('' when it may)."""


@dataclass(frozen=True)
class Decision:
    """The answer to one request: refused (``status`` and ``reason``), or a grant."""

    grant: Grant | None = None
    status: int = 200
    reason: str = ""
    #: The token the request brought in its query: answer with a cookie that keeps it.
    store_token: bool = False
    #: Send the page on to this path of ours (a new seat's address).
    location: str = ""
    #: Serve the page that lives at ``/`` (a seat's address is the same page).
    page: bool = False

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
    #: A reverse proxy on this machine sets X-Forwarded-For: believe its last address (--trust-proxy).
    trust_proxy: bool = False
    #: The class's seats (``serve --class``), or None: no page takes a seat.
    seats: Seats | None = None

    @classmethod
    def for_server(cls, listen_host: str, *, token: str | None = None, viewers: str = WATCH,
                   allow_programs: bool = False, allow_hosts: Iterable[str] = (),
                   allow_origins: Iterable[str] = (), trust_proxy: bool = False) -> "Access":
        """The rules for a server on ``listen_host``: shared beyond this machine or behind a trusted proxy,
        it needs a token (a new one unless given); otherwise only if one is given."""
        if viewers not in (WATCH, "none"):
            raise ValueError(f"viewers must be 'watch' or 'none', not {viewers!r}")
        if token and not well_formed_token(token):
            raise ValueError("--token must be printable ASCII (at most 256 characters) without spaces, "
                             "quotes, commas, semicolons or backslashes")
        origins = {o: _origin_key(o) for o in allow_origins}
        bad = [o for o, key in origins.items() if key is None]
        if bad:
            raise ValueError(f"--allow-origin {bad[0]!r} is not an origin such as https://example.org:8443")
        if token is None and (is_shared(listen_host) or trust_proxy):  # behind a proxy, visitors come from afar
            token = new_token()
        return cls(listen_host=listen_host, token=token or None, viewers=viewers, allow_programs=allow_programs,
                   allowed_hosts=frozenset(h.lower() for h in allow_hosts),
                   allowed_origins=frozenset(origins.values()), trust_proxy=trust_proxy)

    @property
    def cookie_name(self) -> str:
        return f"phototaxis-token-{self.port}"  # cookies are per host, not per port

    # ----------------------------------------------------------- decisions
    def decide(self, headers: Mapping[str, str], path: str, peer: str, *, websocket: bool,
               server_address: str = "") -> Decision:
        """Decide a request from its headers, path (with query), the peer's address and the address the
        connection reached the server at."""
        repeated = next((name for name in SINGLE_HEADERS if len(_all_values(headers, name)) > 1), None)
        if repeated:
            return Decision(status=403, reason=f"this request has more than one {repeated} header; send one")
        host = headers.get("Host")
        if not host or not self.host_allowed(_hostname(host)):
            return Decision(status=403, reason=f"this server does not answer to the host {host!r}; "
                                               f"start it with --allow-host to add a name")
        origin = headers.get("Origin")
        if websocket and origin is not None and not self.origin_allowed(origin, host):
            return Decision(status=403, reason=f"pages from {origin!r} may not connect to this sandbox")
        presented = self._tokens_in(headers, path)
        if not all(well_formed_token(token) for token in presented):
            return Decision(status=403, reason="the token in this request is malformed: use the link printed "
                                               "when the server started")
        address = self.client_address(headers, peer, server_address)
        if self.seats is not None and _seat_path(path) is not None:
            return self._seat(_seat_path(path), address, websocket)
        authorised = self.token is None or any(_same_secret(token, self.token) for token in presented)
        if not authorised and self.seats is not None:  # a lesson: a page without the token is a student's
            if websocket:
                return Decision(status=403, reason="open the students' link: each student gets a world of their own")
            if urlsplit(path).path == "/":
                return Decision(grant=Grant(WATCH, address=address), location=JOIN_PATH)
        if not authorised and self.viewers == "none":
            return Decision(status=403, reason="this sandbox needs the link with its token (?token=...)")
        role = CONTROL if authorised else WATCH
        programs = role == CONTROL and (self.allow_programs or self.local_page(headers, peer, server_address))
        store = authorised and self.token is not None and bool(_query_tokens(path))
        return Decision(grant=Grant(role, programs, address), store_token=store)

    def _seat(self, identity: str, address: str, websocket: bool) -> Decision:
        """A request for the students' link (``identity`` empty) or for a seat's address."""
        assert self.seats is not None
        if not identity:
            if websocket:
                return Decision(status=403, reason="open the students' link in a browser")
            issued = self.seats.issue(address)
            if issued is None:
                return Decision(status=503, reason="the class is full; ask your teacher")
            return Decision(grant=Grant(SEAT, address=address, seat=issued), location=SEAT_PATH + issued)
        why = self.seats.check(identity, address) if SEAT_PATTERN.fullmatch(identity) else "no such seat"
        if why:
            return Decision(status=403, reason=f"{why}: open the students' link again for a world of your own")
        return Decision(grant=Grant(SEAT, address=address, seat=identity), page=not websocket)

    def client_address(self, headers: Mapping[str, str], peer: str, server_address: str = "") -> str:
        """The page's address: behind a trusted proxy the one it forwarded, else the peer's."""
        return self._forwarded(headers, peer, server_address) or peer

    def local_page(self, headers: Mapping[str, str], peer: str, server_address: str = "") -> bool:
        """Whether the request comes from a page on this machine, which may load light programs.

        Behind a trusted proxy, its forwarded address decides. Otherwise the connection must come from
        this machine, carry no proxy header (a proxy on this machine makes every visitor's connection
        local) and, from a browser, be this server's own page: the ``Origin`` a proxied page sends is the
        proxy's, never ``http://`` with this server's port."""
        forwarded = self._forwarded(headers, peer, server_address)
        if forwarded is not None:
            return same_machine(forwarded, server_address)
        if any(name in headers for name in PROXY_HEADERS):
            return False
        return same_machine(peer, server_address) and self._own_page(headers)

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

    def _own_page(self, headers: Mapping[str, str]) -> bool:
        """No ``Origin`` (not a browser page), or the page this server served itself: plain ``http`` on its port."""
        origin = headers.get("Origin")
        if origin is None:
            return True
        key = _origin_key(origin)
        return key == f"http://{_host_key(headers.get('Host', ''))}" and key.endswith(f":{self.port}")

    def _forwarded(self, headers: Mapping[str, str], peer: str, server_address: str) -> str | None:
        """With --trust-proxy, for a connection from this machine (the proxy) that carries
        ``X-Forwarded-For``: the header's last address, the one the proxy added (earlier ones are
        whatever the page sent). Else None: a direct connection, or a proxy this server does not trust."""
        if not self.trust_proxy or not same_machine(peer, server_address):
            return None
        hops = ",".join(_all_values(headers, "X-Forwarded-For")).split(",")
        last = _address_only(hops[-1])
        return last or None

    def _tokens_in(self, headers: Mapping[str, str], path: str) -> list[str]:
        """Every token the request presents: each ``Authorization: token``, each cookie of ours and each
        ``token`` of its query (a blank one too: it is malformed, not absent)."""
        tokens = []
        for authorization in _all_values(headers, "Authorization"):
            if authorization.lower().startswith("token "):
                tokens.append(authorization[6:].strip())
        for cookie in _all_values(headers, "Cookie"):
            tokens += _cookie_values(cookie, self.cookie_name)
        return tokens + _query_tokens(path)

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


def _client_ip(address: str) -> ipaddress.IPv4Address | ipaddress.IPv6Address | None:
    """An address as a client's: an IPv4 address a dual-stack socket reports as ``::ffff:a.b.c.d`` is that IPv4."""
    ip = _ip(address)
    if isinstance(ip, ipaddress.IPv6Address) and ip.ipv4_mapped is not None:
        return ip.ipv4_mapped
    return ip


def _address_only(hop: str) -> str:
    """An address from a proxy header's entry, without the port some proxies add (``[::1]:80``, ``1.2.3.4:80``)."""
    hop = hop.strip()
    if hop.startswith("[") and "]" in hop:
        return hop[1:hop.index("]")]
    if hop.count(":") == 1:
        return hop.split(":", 1)[0]
    return hop


def _same_secret(given: str, token: str) -> bool:
    """Compared in constant time, as bytes: ``hmac.compare_digest`` refuses non-ASCII strings."""
    return hmac.compare_digest(given.encode("utf-8", "surrogateescape"), token.encode("utf-8", "surrogateescape"))


def _all_values(headers: Mapping[str, str], name: str) -> list[str]:
    """Every value of a header that may come more than once (websockets' Headers), or the one of a dict."""
    get_all = getattr(headers, "get_all", None)
    if get_all is not None:
        return list(get_all(name))
    value = headers.get(name)
    return [] if value is None else [value]


def _cookie_values(header: str, name: str) -> list[str]:
    """The values of the cookie ``name`` in a ``Cookie`` header, read by hand: a value that is not a
    cookie-octet must be seen (and refused), not skipped as ``http.cookies`` skips it."""
    values = []
    for pair in header.split(";"):
        key, sep, value = pair.strip().partition("=")
        if sep and key.strip() == name:
            values.append(value.strip())
    return values


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


def _seat_path(path: str) -> str | None:
    """The seat a path names ('' for the students' link itself), or None for any other path."""
    plain = urlsplit(path).path
    if plain in (JOIN_PATH, JOIN_PATH + "/"):
        return ""
    if plain.startswith(SEAT_PATH):
        return plain[len(SEAT_PATH):].rstrip("/") or "-"
    return None


def _query_tokens(path: str) -> list[str]:
    """Every ``token`` of the query, in order (``?token=A&token=B``: both)."""
    return parse_qs(urlsplit(path).query, keep_blank_values=True).get("token", [])


def _own_names() -> frozenset:
    """This machine's names, as a browser on the network may ask for it."""
    names = {socket.gethostname().lower()}
    try:
        names.add(socket.getfqdn().lower())
    except OSError:
        pass
    return frozenset(n for n in names if n)
