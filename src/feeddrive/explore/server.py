"""The explorer's HTTP server: the standard library's threading server, one page, a JSON API.

Routes (all on 127.0.0.1; a request naming another host is refused, so that a web page
elsewhere cannot reach the server through a rebound DNS name; POST bodies must be JSON):

=========================  ===========================================================
``GET /``                  the page (``static/index.html``)
``GET /static/NAME``       the page's script and style; ``plotly.min.js`` from the
                           installed ``plotly`` package (no CDN)
``GET /api/info``          fields with labels and units, presets, drives, compensation
                           modes, the settings the server was started with, warm-up state
``GET /api/state?QUERY``   the settings an address carries, checked
``POST /api/check``        ``{"settings"}`` → messages per field, the set's own knob
                           values, the address query
``POST /api/jobs``         ``{"kind": "simulate"|"linear"|"critical", "settings"}`` → a job
                           (or the messages, status 422)
``GET /api/jobs/ID``       its state, progress and, once done, its result
``POST /api/jobs/ID/cancel``
``POST /api/export``       ``{"settings"}`` → ``{"filename", "toml"}``
``POST /api/import``       ``{"toml", "settings"}`` → the settings the file gives
``GET /api/runs/ID/signals``  every signal of a finished run's Dataset (name, unit,
                           description) and the run's settings
``GET /api/runs/ID/signal?name=N``  one signal, engineering units, peaks kept
``GET /api/runs/ID/data.csv``, ``data.mat``  the run's every sample (download)
``POST /api/measured``     ``{"csv", "name"}`` → a measured position trace to overlay
``POST /api/machine``      ``{"machine", "radius", "feed", "acceleration"}`` → a job: a
                           machine's XY circle, its path and contour error
                           (``feeddrive.explore.machine_path``)
=========================  ===========================================================
"""

from __future__ import annotations

import json
import socket
import sys
import threading
import time
import traceback
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from typing import Any
from urllib.parse import urlsplit

from .. import __version__
from ..parameters import PRESETS, ParameterError
from . import compute
from .jobs import Busy, Job, Jobs
from .runs import Runs
from .settings import (
    DEFAULTS,
    FIELDS,
    MAX_DURATION,
    check,
    compensation_modes,
    export_toml,
    from_query,
    import_toml,
    normalise,
)

MAX_BODY = 4 * 1024 * 1024  # [bytes] a parameter file is a few kB
#: [s] a connection that sends nothing for this long is closed (a slow or stalled client)
READ_TIMEOUT = 20.0
#: connections served at once; one more is answered 503 and closed
MAX_CONNECTIONS = 32
#: deepest JSON nesting a request may have (the page sends 2 levels)
MAX_JSON_DEPTH = 32
_STATIC = {"index.html": "text/html; charset=utf-8",
           "explore.js": "text/javascript; charset=utf-8",
           "explore.css": "text/css; charset=utf-8"}


class MissingDependency(ImportError):
    """The explorer's optional dependency is not installed."""


def plotly_js() -> bytes:
    """plotly.js as the installed ``plotly`` package ships it (its offline copy).

    Returns
    -------
    bytes
        The minified script.

    Raises
    ------
    MissingDependency
        When plotly is not installed.
    """
    try:
        root = resources.files("plotly")
    except ModuleNotFoundError:
        raise MissingDependency(
            "the explorer needs plotly (it serves the page plotly's own copy of plotly.js); "
            "install it with: pip install 'feeddrive[explore]'") from None
    return (root / "package_data" / "plotly.min.js").read_bytes()


def _static(name: str) -> bytes:
    return (resources.files("feeddrive.explore") / "static" / name).read_bytes()


class Explorer:
    """State of one explorer: the settings it started with, its jobs, simulation speed.

    Parameters
    ----------
    initial : dict, optional
        The starting settings (from the ``feeddrive explore`` options).
    """

    def __init__(self, initial: dict[str, Any] | None = None) -> None:
        self.initial = normalise(initial)
        self.jobs = Jobs()
        self.runs = Runs()  # finished simulations for the signal picker and downloads
        self.ready = threading.Event()
        self._rates: dict[str, float] = {}  # [s of wall time per s simulated] by drive
        self._plotly: bytes | None = None

    # ------------------------------------------------------------ work

    def warm_up(self) -> Job:
        """Load (or, on a fresh install, compile) the solver for the drives of the starting
        parameter set, so that the first click is answered at once.

        Returns
        -------
        Job
            The warm-up job.
        """

        def work(job: Job) -> None:
            first = check(self.initial)
            drives = list(dict.fromkeys((first.drive, "cdfs", "ddfs")))
            for k, drive in enumerate(drives):
                job.report(k, len(drives), f"preparing the solver for the {drive.upper()}")
                # 1 mm/s creeps on the CDFS: the stick-slip metrics get loaded too
                trial = check({**first.settings, "drive": drive, "table_speed": "1",
                               "duration": "2"})
                if not trial.ok:
                    continue  # e.g. a drive this parameter set cannot build
                compute.run_simulation(trial, _quiet)
                started = time.perf_counter()
                compute.run_simulation(trial, _quiet)
                self._rates[drive] = (time.perf_counter() - started) / trial.duration
            if first.ok:
                job.report(len(drives), len(drives) + 1, "linear analysis")
                compute.run_linear(first, _quiet)
            self.ready.set()

        job = self.jobs.start("warmup", work)

        def ready_anyway() -> None:  # a warm-up that failed must not keep the page waiting
            self.jobs.wait(job.id, 600)
            self.ready.set()

        threading.Thread(target=ready_anyway, daemon=True).start()
        return job

    def start(self, kind: str, settings: dict[str, Any]) -> tuple[Job | None, dict[str, Any]]:
        """Check the page's settings and start a job of ``kind`` with them.

        Parameters
        ----------
        kind : str
            ``"simulate"``, ``"linear"`` or ``"critical"``.
        settings : dict
            The page's settings.

        Returns
        -------
        job : Job or None
            The started job; None when a setting was refused.
        checked : dict
            The check's messages and values (``Checked.as_dict``).
        """
        checked = check(settings)
        if not checked.ok:
            return None, checked.as_dict()
        if kind == "simulate":
            rate = self._rates.get(checked.drive)

            def simulate_work(job: Job) -> Any:
                started = time.perf_counter()
                out = compute.run_simulation(
                    checked, job.report,
                    keep=lambda result: self.runs.put(job.id, result, checked.settings))
                out["run_id"] = job.id
                wall = time.perf_counter() - started
                self._rates[checked.drive] = wall / checked.duration
                out["wall_time_s"] = wall
                return out

            job = self.jobs.start(kind, simulate_work, _error_field,
                                  expected_s=None if rate is None else rate * checked.duration,
                                  text=f"simulating {checked.duration:g} s of the "
                                       f"{checked.drive.upper()}")
        elif kind == "linear":
            job = self.jobs.start(kind, lambda j: compute.run_linear(checked, j.report),
                                  _error_field)
        elif kind == "critical":
            total = compute.estimated_trials()
            job = self.jobs.start(kind, lambda j: compute.run_critical(checked, j.report),
                                  _error_field, text=f"trial 1 of about {total}",
                                  total=total)
        else:
            raise ParameterError("kind", kind, "expected simulate, linear or critical")
        return job, checked.as_dict()

    def start_machine(self, body: dict[str, Any]) -> Job:
        """Check a machine request (``feeddrive.explore.machine_path.check_request``) and
        start a job that simulates its XY circle.

        Parameters
        ----------
        body : dict
            ``machine`` (a built-in name or a machine file's TOML text), ``radius`` [mm],
            ``feed`` [mm/min], ``acceleration`` [mm/s^2].

        Returns
        -------
        Job
            The started job (kind ``"machine"``).

        Raises
        ------
        ParameterError
            For a refused field, naming it (before any work).
        """
        from .machine_path import check_request, run_machine_path

        machine, contour = check_request(body)
        return self.jobs.start(
            "machine", lambda j: run_machine_path(machine, contour, j.report), _error_field,
            text=f"simulating {contour.duration:.3g} s of {machine.name}",
            total=contour.duration)

    def info(self) -> dict[str, Any]:
        """What the page needs to build its form.

        Returns
        -------
        dict
            Version, presets, drives, fields (name, label, unit, group, option, path, help),
            compensation modes, the fields' units, the starting settings and defaults, the
            longest duration [s], the critical search's trial count, whether the solver is
            ready, the built-in machines and the machine panel's defaults
            (``feeddrive.explore.machine_path``).
        """
        from ..machine import MACHINES
        from ..model import drive_names
        from .machine_path import DEFAULTS as MACHINE_DEFAULTS

        return {
            "version": __version__, "presets": list(PRESETS), "drives": list(drive_names()),
            "machines": list(MACHINES), "machine_defaults": MACHINE_DEFAULTS,
            "fields": [{"name": f.name, "label": f.label, "unit": f.unit, "group": f.group,
                        "option": f.option, "path": f.path, "help": f.help} for f in FIELDS],
            "compensation_modes": list(compensation_modes()),
            "units": _initial_units(self.initial),
            "initial": self.initial, "defaults": DEFAULTS, "max_duration_s": MAX_DURATION,
            "critical_trials": compute.estimated_trials(), "ready": self.ready.is_set(),
        }

    def plotly(self) -> bytes:
        """plotly.js, read once and kept.

        Returns
        -------
        bytes
            The script.
        """
        if self._plotly is None:
            self._plotly = plotly_js()
        return self._plotly


def _initial_units(initial: dict[str, Any]) -> dict[str, str]:
    """The fields' units for the starting parameter set (its velocity_gain_basis)."""
    from .settings import field_units

    checked = check(initial)
    return field_units(checked.base)


def _quiet(done: float, total: float, text: str) -> None:
    """Progress of work no page waits for."""


def _error_field(err: BaseException) -> str | None:
    """The page field a failed run's message belongs beside."""
    text = str(err)
    if text.startswith("--table-speed"):  # a zero command, refused as the CLI refuses it
        return "table_speed"
    return None


class ExplorerServer(ThreadingHTTPServer):
    """One thread per connection, at most ``MAX_CONNECTIONS`` at once; each connection
    is closed after ``READ_TIMEOUT`` s without a byte (``Handler.timeout``).

    A connection over the cap takes the slot of the connection that has waited longest for
    its next request (idle, or still sending its request line, headers or body), which is
    closed; only when every slot is busy computing an answer is it answered 503.  A local
    process holding every slot with half-open sockets, reconnected as they time out, kept
    every real request out (issue 39 item 7).

    Parameters
    ----------
    port : int
        The port; 0 for a free one.
    explorer : Explorer
        The explorer state the handlers serve.
    host : str, default "127.0.0.1"
        The address to listen on.
    """

    daemon_threads = True
    # the listen backlog: connections past the cap are accepted (and answered 503) at once,
    # not left unaccepted in the kernel's queue
    request_queue_size = 2 * MAX_CONNECTIONS

    def __init__(self, port: int, explorer: Explorer, host: str = "127.0.0.1") -> None:
        self.explorer = explorer
        self._slots = threading.BoundedSemaphore(MAX_CONNECTIONS)
        self._waiting: dict[Any, float] = {}  # connection → since when it waits [monotonic s]
        self._waiting_lock = threading.Lock()
        super().__init__((host, port), Handler)

    def waiting(self, connection: Any, waits: bool) -> None:
        """Mark a connection as waiting for its client (it may give its slot away) or as
        busy with a request (it may not).

        Parameters
        ----------
        connection : socket.socket
            The connection.
        waits : bool
            Whether it now waits for its client.
        """
        with self._waiting_lock:
            if waits:
                self._waiting.setdefault(connection, time.monotonic())
            else:
                self._waiting.pop(connection, None)

    def _evict_oldest_waiting(self) -> bool:
        """Close the connection that has waited longest for its client; False if none."""
        with self._waiting_lock:
            if not self._waiting:
                return False
            oldest = min(self._waiting, key=self._waiting.__getitem__)
            del self._waiting[oldest]
        try:
            oldest.shutdown(socket.SHUT_RDWR)  # its thread's read returns: it ends
        except OSError:
            pass
        return True

    def process_request(self, request: Any, client_address: Any) -> None:
        if not self._slots.acquire(blocking=False):
            if not (self._evict_oldest_waiting() and self._slots.acquire(timeout=2.0)):
                _refuse_connection(request)
                return
        try:
            super().process_request(request, client_address)
        except BaseException:
            self._slots.release()
            raise

    def process_request_thread(self, request: Any, client_address: Any) -> None:
        try:
            super().process_request_thread(request, client_address)
        finally:
            self.waiting(request, False)
            self._slots.release()

    @property
    def port(self) -> int:
        """The port the server listens on."""
        return int(self.server_address[1])

    def handle_error(self, request: Any, client_address: Any) -> None:
        """A browser that closes a kept-alive connection resets it while the server waits for
        the next request: nothing went wrong, so no traceback in the user's terminal.  Any
        other error is printed as ``socketserver`` prints it."""
        if isinstance(sys.exc_info()[1], ConnectionError | TimeoutError):
            return
        super().handle_error(request, client_address)

    @property
    def url(self) -> str:
        """The page's address, ``http://127.0.0.1:<port>/``."""
        return f"http://127.0.0.1:{self.port}/"


def _refuse_connection(sock: Any) -> None:
    """Answer a connection over the cap with 503 and close it (never blocks long)."""
    try:
        sock.settimeout(0.1)
        body = b'{"error":"too many connections to the explorer; retry"}'
        sock.sendall(b"HTTP/1.1 503 Service Unavailable\r\nContent-Type: application/json"
                     b"\r\nContent-Length: " + str(len(body)).encode() +
                     b"\r\nConnection: close\r\n\r\n" + body)
        sock.shutdown(socket.SHUT_WR)
        sock.recv(65536)  # what the client sent, briefly: closing unread would reset the answer
    except OSError:
        pass
    finally:
        try:
            sock.close()
        except OSError:
            pass


def _json_depth(raw: bytes) -> int:
    """Deepest [ / { nesting of JSON text (strings skipped), without parsing it."""
    depth = deepest = 0
    in_string = escaped = False
    for byte in raw:
        if in_string:
            if escaped:
                escaped = False
            elif byte == 0x5C:  # backslash
                escaped = True
            elif byte == 0x22:  # quote
                in_string = False
        elif byte == 0x22:
            in_string = True
        elif byte in (0x5B, 0x7B):
            depth += 1
            deepest = max(deepest, depth)
        elif byte in (0x5D, 0x7D):
            depth -= 1
    return deepest


def _settings_of(body: dict[str, Any], key: str = "settings") -> dict[str, Any] | None:
    """``body[key]``: absent, or an object of field values; anything else is a 400 naming
    the key.  (A field holding a list or an object is refused beside the field by the
    check, as any value that is not a number; its nesting is bounded by the body's.)"""
    value = body.get(key)
    if value is None:
        return None
    if not isinstance(value, dict):
        raise _HttpError(HTTPStatus.BAD_REQUEST, f"'{key}' must be an object of field "
                         f"values, not {type(value).__name__}")
    for name, item in value.items():
        if isinstance(item, int) and not isinstance(item, bool) and abs(item) > 1e300:
            raise _HttpError(HTTPStatus.BAD_REQUEST, f"'{key}.{name[:40]}': a number too "
                             "large for a field")
    return value


#: the routes and the method each takes (prefixes end with "/"; the module lists them)
_ROUTES = {"/": ("GET",), "/index.html": ("GET",), "/static/": ("GET",), "/api/info": ("GET",),
           "/api/state": ("GET",), "/favicon.ico": ("GET",), "/api/runs/": ("GET",),
           "/api/check": ("POST",), "/api/jobs": ("POST",), "/api/machine": ("POST",),
           "/api/export": ("POST",), "/api/import": ("POST",), "/api/measured": ("POST",)}


def _methods_of(path: str) -> tuple[str, ...]:
    """The methods ``path`` is answered for: ``()`` for no route.  A job's poll is a GET, its
    cancel a POST."""
    if path.startswith("/api/jobs/"):
        return ("POST",) if path.endswith("/cancel") else ("GET",)
    if path in _ROUTES:
        return _ROUTES[path]
    return next((m for p, m in _ROUTES.items() if p.endswith("/") and p != "/"
                 and path.startswith(p)), ())


class Handler(BaseHTTPRequestHandler):
    server: ExplorerServer
    protocol_version = "HTTP/1.1"
    timeout = READ_TIMEOUT  # socket timeout: a stalled client is dropped

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002  (base signature)
        """Quiet: the terminal shows the address and errors, not every poll."""

    def handle_one_request(self) -> None:
        """One request; while its request line and headers are awaited, the connection may
        give its slot to a new one (:class:`ExplorerServer`)."""
        self.server.waiting(self.connection, True)
        super().handle_one_request()

    def parse_request(self) -> bool:
        ok = super().parse_request()  # the headers are read: the request is being served
        self.server.waiting(self.connection, False)
        return ok

    # ------------------------------------------------------------ plumbing

    def _send(self, status: int, body: bytes, content_type: str,
              cache: str = "no-store") -> None:
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", cache)
        self.send_header("X-Content-Type-Options", "nosniff")
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _json(self, status: int, data: Any) -> None:
        body = json.dumps(data, allow_nan=False, separators=(",", ":")).encode("utf-8")
        self._send(status, body, "application/json; charset=utf-8")

    def _host_ok(self) -> bool:
        host = (self.headers.get("Host") or "").lower()
        port = self.server.port
        return host in (f"127.0.0.1:{port}", f"localhost:{port}", "127.0.0.1", "localhost")

    def _origin_ok(self) -> bool:
        """A POST from a page comes with its Origin: it must be the explorer's own (a page
        elsewhere cannot start runs); a request without one (curl, a script) is allowed."""
        origin = self.headers.get("Origin")
        if origin is None:
            return True
        port = self.server.port
        return origin.lower() in (f"http://127.0.0.1:{port}", f"http://localhost:{port}")

    def send_error(self, code: int, message: str | None = None,
                   explain: str | None = None) -> None:
        """The errors the standard library answers itself (a malformed request line, a
        header too long, an unknown method) as JSON like every other answer, the connection
        closed (it sent an HTML page: an outside check, 2026-12-07)."""
        self.close_connection = True
        if self.request_version == "HTTP/0.9":  # a line it could not read: answer in HTTP/1.0
            self.request_version = "HTTP/1.0"
        text = message or HTTPStatus(code).phrase
        body = json.dumps({"error": text}).encode("utf-8")
        try:
            self.send_response(code, text)
            self.send_header("Content-Type", "application/json; charset=utf-8")
            self.send_header("Connection", "close")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            if self.command != "HEAD" and code >= 200 and code not in (204, 304):
                self.wfile.write(body)
        except (BrokenPipeError, ConnectionResetError, TimeoutError):
            pass

    def _refuse_method(self) -> None:
        """A method no route takes: 405 naming the ones the address takes."""
        if not self._host_ok():
            self._json(HTTPStatus.FORBIDDEN, {"error": "the explorer answers 127.0.0.1 only"})
            return
        path = urlsplit(self.path).path
        allowed = _methods_of(path) or ("GET", "POST")
        self.close_connection = True  # a body it may have sent is not read
        self._json(HTTPStatus.METHOD_NOT_ALLOWED,
                   {"error": f"{self.command} is not answered here; {path[:80]} takes "
                             f"{' or '.join(allowed)}"})

    do_PUT = do_DELETE = do_PATCH = do_OPTIONS = _refuse_method  # noqa: N815 (the base's names)

    def _body(self) -> Any:
        ctype = (self.headers.get("Content-Type") or "").split(";")[0].strip().lower()
        if ctype != "application/json":
            raise _HttpError(HTTPStatus.UNSUPPORTED_MEDIA_TYPE, "send JSON")
        if "chunked" in (self.headers.get("Transfer-Encoding") or "").lower():
            self.close_connection = True  # where the body ends is not read
            raise _HttpError(HTTPStatus.LENGTH_REQUIRED, "send the body with a Content-Length "
                             "(a chunked body is not read)")
        text = (self.headers.get("Content-Length") or "0").strip()
        if not text.isdigit() or not text.isascii():
            self.close_connection = True  # where the body ends is unknown
            raise _HttpError(HTTPStatus.BAD_REQUEST, f"Content-Length {text[:20]!r}: expected "
                             "a whole number of bytes ≥ 0")
        length = int(text)
        if length > MAX_BODY:
            self.close_connection = True
            raise _HttpError(HTTPStatus.REQUEST_ENTITY_TOO_LARGE,
                             f"request larger than {MAX_BODY // 1024 // 1024} MB")
        try:
            self.server.waiting(self.connection, True)  # a body that stalls may be evicted
            raw = self.rfile.read(length)
            self.server.waiting(self.connection, False)
        except TimeoutError:
            self.close_connection = True
            raise _HttpError(HTTPStatus.REQUEST_TIMEOUT, f"the request body did not arrive "
                             f"within {READ_TIMEOUT:g} s") from None
        if len(raw) < length:
            self.close_connection = True
            raise _HttpError(HTTPStatus.BAD_REQUEST, "the request body ended early")
        if _json_depth(raw) > MAX_JSON_DEPTH:
            raise _HttpError(HTTPStatus.BAD_REQUEST, f"JSON nested more than {MAX_JSON_DEPTH} "
                             "deep")
        try:
            data = json.loads(raw or b"{}")
        except (ValueError, RecursionError):  # JSONDecodeError, UnicodeDecodeError, huge ints
            raise _HttpError(HTTPStatus.BAD_REQUEST, "not valid JSON") from None
        if not isinstance(data, dict):
            raise _HttpError(HTTPStatus.BAD_REQUEST, "expected a JSON object")
        return data

    def _dispatch(self, method: str) -> None:
        if not self._host_ok():
            self._json(HTTPStatus.FORBIDDEN, {"error": "the explorer answers 127.0.0.1 only"})
            return
        if self.command == "POST" and not self._origin_ok():
            self.close_connection = True
            self._json(HTTPStatus.FORBIDDEN, {"error": "requests from other pages are refused "
                                              "(Origin is not the explorer's address)"})
            return
        url = urlsplit(self.path)
        try:
            self._route(method, url.path, url.query)
        except _HttpError as err:
            self._json(err.status, {"error": err.message})
        except (BrokenPipeError, ConnectionResetError, TimeoutError):
            self.close_connection = True
        except Exception as err:  # the server must outlive any bug; the page shows it
            traceback.print_exc(file=sys.stderr)
            self._json(HTTPStatus.INTERNAL_SERVER_ERROR,
                       {"error": f"internal error: {type(err).__name__}: {err}"})

    def do_GET(self) -> None:  # noqa: N802  (BaseHTTPRequestHandler's name)
        """Answer a GET request: the page and its static files, the form's info, the state of an
        address, job polls and a kept run's signals and CSV (the module lists the routes)."""
        self._dispatch("GET")

    def do_HEAD(self) -> None:  # noqa: N802
        """Answer a HEAD request as a GET."""
        self._dispatch("GET")

    def do_POST(self) -> None:  # noqa: N802
        """Answer a POST request: check settings, start or cancel a job, import or export a
        parameter file, load a measured trace (the module lists the routes)."""
        self._dispatch("POST")

    # ------------------------------------------------------------ routes

    def _route(self, method: str, path: str, query: str) -> None:
        ex = self.server.explorer
        if path.startswith("/api/runs/") or path == "/api/measured":
            self._route_runs(method, path, query)
            return
        if method == "GET":
            if path in ("/", "/index.html"):
                self._send(200, _static("index.html"), _STATIC["index.html"], "no-cache")
            elif path == "/static/plotly.min.js":
                self._send(200, ex.plotly(), "text/javascript; charset=utf-8",
                           "max-age=86400")
            elif path.startswith("/static/") and path[8:] in _STATIC:
                name = path[8:]
                self._send(200, _static(name), _STATIC[name], "no-cache")
            elif path == "/api/info":
                self._json(200, ex.info())
            elif path == "/api/state":
                settings, errors = from_query(query)
                checked = check(settings).as_dict()
                checked["errors"] = {**checked["errors"], **errors}
                self._json(200, {"settings": settings, **checked})
            elif path.startswith("/api/jobs/"):
                job = ex.jobs.get(path.rsplit("/", 1)[-1])
                if job is None:
                    raise _HttpError(HTTPStatus.NOT_FOUND, "no such run")
                self._json(200, job.as_dict())
            elif path == "/favicon.ico":
                self._send(204, b"", "image/x-icon", "max-age=86400")
            elif "POST" in _methods_of(path):
                raise _HttpError(HTTPStatus.METHOD_NOT_ALLOWED, f"POST to {path}")
            else:
                raise _HttpError(HTTPStatus.NOT_FOUND, f"no page {path}")
            return
        if _methods_of(path) == ("GET",):
            self.close_connection = True  # its body is not read
            raise _HttpError(HTTPStatus.METHOD_NOT_ALLOWED, f"GET {path}")
        body = self._body()
        given = _settings_of(body)
        if path == "/api/check":
            self._json(200, check(given).as_dict())
        elif path == "/api/jobs":
            try:
                job, checked = ex.start(str(body.get("kind"))[:40], given or {})
            except Busy as err:
                raise _HttpError(HTTPStatus.TOO_MANY_REQUESTS, str(err)) from None
            except ParameterError as err:
                raise _HttpError(HTTPStatus.BAD_REQUEST, str(err)) from None
            if job is None:
                self._json(HTTPStatus.UNPROCESSABLE_ENTITY, checked)
            else:
                self._json(HTTPStatus.ACCEPTED, {**job.as_dict(), "check": checked})
        elif path == "/api/machine":
            if not isinstance(body, dict):
                raise _HttpError(HTTPStatus.BAD_REQUEST, "expected a JSON object")
            try:
                job = ex.start_machine(body)
            except Busy as err:
                raise _HttpError(HTTPStatus.TOO_MANY_REQUESTS, str(err)) from None
            except ParameterError as err:
                field = err.field if err.field in ("radius", "feed", "acceleration") \
                    else "machine"
                self._json(HTTPStatus.UNPROCESSABLE_ENTITY, {"errors": {field: str(err)}})
                return
            self._json(HTTPStatus.ACCEPTED, job.as_dict())
        elif path.startswith("/api/jobs/") and path.endswith("/cancel"):
            job = ex.jobs.cancel(path.split("/")[3])
            if job is None:
                raise _HttpError(HTTPStatus.NOT_FOUND, "no such run")
            self._json(200, job.as_dict())
        elif path == "/api/export":
            done = check(given)
            if not done.ok:
                self._json(HTTPStatus.UNPROCESSABLE_ENTITY, done.as_dict())
                return
            name = done.params.name if done.params else "feeddrive"
            self._json(200, {"filename": f"{_safe(name)}-{done.drive}.toml",
                             "toml": export_toml(done)})
        elif path == "/api/import":
            text = body.get("toml")
            if not isinstance(text, str):
                raise _HttpError(HTTPStatus.BAD_REQUEST, "expected the file's text in 'toml'")
            try:
                settings = import_toml(text, given)
            except ParameterError as err:
                self._json(HTTPStatus.UNPROCESSABLE_ENTITY, {"errors": {"import": str(err)}})
                return
            self._json(200, {"settings": settings, **check(settings).as_dict()})
        else:
            raise _HttpError(HTTPStatus.NOT_FOUND, f"no page {path}")


    # ------------------------------------------------------------ runs (issue 23)

    def _route_runs(self, method: str, path: str, query: str) -> None:
        """A finished run's signals and downloads, and a measured trace to overlay."""
        from urllib.parse import parse_qs

        from . import runs

        ex = self.server.explorer
        if path == "/api/measured":
            if method != "POST":
                raise _HttpError(HTTPStatus.METHOD_NOT_ALLOWED, "POST a measured trace")
            body = self._body()
            text, name = body.get("csv"), body.get("name") or "measured.csv"
            if not isinstance(text, str) or not isinstance(name, str):
                raise _HttpError(HTTPStatus.BAD_REQUEST, "expected the file's text in 'csv'")
            try:
                self._json(200, runs.measured_trace(text, name))
            except ValueError as err:
                self._json(HTTPStatus.UNPROCESSABLE_ENTITY, {"error": str(err)})
            return
        if method != "GET":
            raise _HttpError(HTTPStatus.METHOD_NOT_ALLOWED, "GET a run's signals")
        parts = path.split("/")  # "", "api", "runs", ID, what
        if len(parts) != 5:
            raise _HttpError(HTTPStatus.NOT_FOUND, f"no page {path}")
        kept = ex.runs.get(parts[3])
        if kept is None:
            raise _HttpError(HTTPStatus.NOT_FOUND, "no such run (finished runs are kept "
                             f"{runs.KEEP_RUNS} at a time)")
        result, settings = kept
        what = parts[4]
        if what == "signals":
            self._json(200, {"run_id": parts[3], "settings": settings,
                             "signals": runs.signal_list(result)})
        elif what == "signal":
            name = (parse_qs(query).get("name") or [""])[0]
            try:
                self._json(200, runs.signal(result, name))
            except KeyError:
                raise _HttpError(HTTPStatus.NOT_FOUND, f"the run has no signal {name!r}"
                                 ) from None
        elif what in ("data.csv", "data.mat"):
            fmt = what.rsplit(".", 1)[1]
            body = runs.export(result, fmt)
            filename = f"feeddrive-{_safe(settings.get('drive', 'run'))}-{parts[3]}.{fmt}"
            self.send_response(200)
            self.send_header("Content-Type", "text/csv; charset=utf-8" if fmt == "csv"
                             else "application/octet-stream")
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Content-Disposition", f'attachment; filename="{filename}"')
            self.send_header("Cache-Control", "no-store")
            self.send_header("X-Content-Type-Options", "nosniff")
            self.end_headers()
            if self.command != "HEAD":
                self.wfile.write(body)
        else:
            raise _HttpError(HTTPStatus.NOT_FOUND, f"no page {path}")


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "-" for c in name)[:60] or "feeddrive"


class _HttpError(Exception):
    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = int(status)
        self.message = message


def make_server(port: int = 0, initial: dict[str, Any] | None = None, *,
                warm_up: bool = True) -> ExplorerServer:
    """A server on 127.0.0.1:``port`` (0: a free port), not yet serving; raises
    :class:`MissingDependency` without plotly and :class:`OSError` when the port is taken.

    Parameters
    ----------
    port : int, default 0
        The port; 0 for a free one.
    initial : dict, optional
        The starting settings.
    warm_up : bool, default True
        Start loading the solver at once.

    Returns
    -------
    ExplorerServer
        The server.
    """
    explorer = Explorer(initial)
    explorer.plotly()  # fail now, not on the first page load
    server = ExplorerServer(port, explorer)
    if warm_up:
        explorer.warm_up()
    else:
        explorer.ready.set()
    return server


def serve_in_thread(port: int = 0, initial: dict[str, Any] | None = None, *,
                    warm_up: bool = True) -> ExplorerServer:
    """Start a server in a daemon thread (tests, notebooks); stop it with ``shutdown()``.

    Parameters
    ----------
    port : int, default 0
        The port; 0 for a free one.
    initial : dict, optional
        The starting settings.
    warm_up : bool, default True
        Start loading the solver at once.

    Returns
    -------
    ExplorerServer
        The running server.

    Examples
    --------
    >>> import json, urllib.request
    >>> from feeddrive.explore import serve_in_thread
    >>> server = serve_in_thread(warm_up=False)
    >>> url = f"http://127.0.0.1:{server.server_address[1]}/api/info"
    >>> with urllib.request.urlopen(url) as reply:
    ...     info = json.load(reply)
    >>> server.shutdown()
    >>> server.server_close()
    >>> print("wang2021" in info["presets"], info["max_duration_s"])
    True 120.0
    """
    server = make_server(port, initial, warm_up=warm_up)
    threading.Thread(target=server.serve_forever, name="feeddrive-explore", daemon=True
                     ).start()
    return server
