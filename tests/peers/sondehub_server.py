"""A local SondeHub-Amateur test server, written from the published API (projecthorus/
sondehub-infra: swagger.yaml, and what its telemetry and listener handlers check), for stx's
tests. Standard library only.

It checks what the real one checks and somewhat more where the real one would fail with a 500:
a gzip body decompresses (else 400), the body is JSON (else 400) and, for telemetry, an array
of points; each point carries the swagger's required fields, `lat`/`lon`/`alt` and the other
numeric fields are JSON numbers (a boolean is not one), `sats` is an integer, `datetime` and
`time_received` are `YYYY-MM-DDTHH:MM:SS[.ffffff]Z`, `uploader_position` is three numbers, and
`dev` is refused. A point refused goes to the answer's `errors` (202); one whose time is more
than 60 s ahead, or further from now than the window (24 h, `--window-s`) without
`historical: true`, or with a default callsign, is kept hidden with a warning (202).

Faults, set on the control port (`POST /fault`, a JSON object; each for the next `count`
telemetry requests unless said): `{"down_s": S}` closes the API's listening socket for S
seconds (connections refused, as a server down); `{"status": 500, "count": N}` answers N
requests with that status and keeps nothing; `{"slow_s": S, "count": N}` keeps the points and
answers S seconds late; `{"reject_first": true, "count": N}` answers 202 with an error for the
first point of each of N requests (that point not kept).

`GET /received` on the control port: every request (method, path, headers, status, the body's
points with each field's Python type) and the points and listeners kept.

Usage: sondehub_server.py [--window-s S]. Prints one line `{"api": PORT, "control": PORT}`
(both on 127.0.0.1), then serves until killed or stdin closes.
"""

import datetime
import json
import re
import sys
import threading
import time
import zlib
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

REQUIRED = ["software_name", "software_version", "uploader_callsign", "time_received",
            "payload_callsign", "datetime", "lat", "lon", "alt"]
NUMBERS = ["lat", "lon", "alt", "frequency", "temp", "humidity", "vel_h", "vel_v", "pressure",
           "heading", "batt", "sats", "snr", "rssi"]
TIME_FIELDS = ["datetime", "time_received"]
TIME_RE = re.compile(r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(\.\d{1,6})?Z$")
HIDDEN_PAYLOADS = {"4FSKTEST", "4FSKTEST-V2", "4FSKTEST-V3", "N0CALL"}
HIDDEN_UPLOADERS = {"MYCALL", "N0CALL"}
FUTURE_S = 60


class State:
    def __init__(self, window_s):
        self.lock = threading.Lock()
        self.window_s = window_s
        self.requests = []
        self.points = []
        self.listeners = []
        self.faults = []

    def take_fault(self, key):
        """The first fault with `key` still counting down, counted once."""
        with self.lock:
            for f in self.faults:
                if key in f and f.get("count", 1) > 0:
                    f["count"] = f.get("count", 1) - 1
                    return f
        return None


def is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def parse_time(text):
    if not isinstance(text, str) or not TIME_RE.match(text):
        return None
    try:
        return datetime.datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        return None


def check_point(p, window_s):
    """(error or None, [warnings]) for one point, as the real handler judges it."""
    if not isinstance(p, dict):
        return "a point is not an object", []
    for f in REQUIRED:
        if f not in p:
            return f"Missing {f} field", []
    for f in NUMBERS:
        if f in p and not is_number(p[f]):
            return f"{f} should be a number", []
    if "sats" in p and not isinstance(p["sats"], int):
        return "sats should be an integer", []
    for f in ["software_name", "software_version", "uploader_callsign", "payload_callsign"]:
        if not isinstance(p[f], str):
            return f"{f} should be a string", []
    times = {}
    for f in TIME_FIELDS:
        times[f] = parse_time(p[f])
        if times[f] is None:
            return f"Unable to parse {f} (YYYY-MM-DDTHH:MM:SS.ffffffZ)", []
    if "uploader_position" in p:
        u = p["uploader_position"]
        if not (isinstance(u, list) and len(u) == 3 and all(is_number(x) for x in u)):
            return "uploader_position should be [lat, lon, alt]", []
    if "historical" in p and not isinstance(p["historical"], bool):
        return "historical should be a boolean", []
    if "upload_time" in p:
        return "upload_time is set by the server", []
    if "dev" in p:
        return ("All checks passed however payload contained dev flag so will not be "
                "uploaded to the database"), []
    warnings = []
    delta = (datetime.datetime.now(datetime.timezone.utc) - times["datetime"]).total_seconds()
    if delta < -FUTURE_S:
        warnings.append(f"Payload reported time too far in the future (threshold {FUTURE_S} s)")
    if not p.get("historical", False) and abs(delta) > window_s:
        warnings.append(f"Payload reported time too far from current UTC time "
                        f"(threshold {window_s} s)")
    if p["payload_callsign"] in HIDDEN_PAYLOADS or p["uploader_callsign"] in HIDDEN_UPLOADERS:
        warnings.append("testing or default callsign: hidden")
    return None, warnings


def typed(point):
    if not isinstance(point, dict):
        return None
    return {k: type(v).__name__ for k, v in point.items()}


class Api(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"
    state = None

    def log_message(self, *args):
        pass

    def answer(self, status, body, content_type="text/plain"):
        data = body.encode() if isinstance(body, str) else body
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(data)))
        # One request per connection: a server taken down refuses the next request at once
        # rather than answering it on a connection kept from before.
        self.send_header("Connection", "close")
        self.close_connection = True
        self.end_headers()
        self.wfile.write(data)

    def read_body(self):
        raw = self.rfile.read(int(self.headers.get("Content-Length", "0")))
        if self.headers.get("Content-Encoding", "").lower() == "gzip":
            raw = zlib.decompress(raw, 16 + zlib.MAX_WBITS)
        return json.loads(raw)

    def do_PUT(self):
        s = self.state
        record = {"method": "PUT", "path": self.path, "at": time.time(),
                  "headers": {k.lower(): v for k, v in self.headers.items()}}
        try:
            body = self.read_body()
        except zlib.error:
            record["status"] = 400
            self.finish_record(record)
            return self.answer(400, "Could not decompress")
        except (ValueError, UnicodeDecodeError):
            record["status"] = 400
            self.finish_record(record)
            return self.answer(400, "Not valid json")
        if self.path == "/amateur/telemetry":
            return self.telemetry(record, body)
        if self.path == "/amateur/listeners":
            return self.listener(record, body)
        record["status"] = 404
        self.finish_record(record)
        return self.answer(404, "not found")

    def finish_record(self, record):
        with self.state.lock:
            self.state.requests.append(record)

    def telemetry(self, record, body):
        s = self.state
        record["points"] = [typed(p) for p in body] if isinstance(body, list) else None
        if not isinstance(body, list):
            record["status"] = 400
            self.finish_record(record)
            return self.answer(400, "the body must be an array of points")
        fault = s.take_fault("status")
        if fault:
            record["status"] = fault["status"]
            self.finish_record(record)
            return self.answer(fault["status"], "test fault")
        reject = s.take_fault("reject_first")
        errors, warnings = [], []
        for i, p in enumerate(body):
            if reject and i == 0:
                errors.append({"error_message": "test fault: refused", "payload": p})
                continue
            error, warns = check_point(p, s.window_s)
            if error:
                errors.append({"error_message": error, "payload": p})
                continue
            for w in warns:
                warnings.append({"warning_message": w, "payload": p})
            kept = dict(p)
            kept["telemetry_hidden"] = bool(warns)
            kept["upload_time"] = datetime.datetime.now(datetime.timezone.utc).isoformat()
            with s.lock:
                s.points.append(kept)
        slow = s.take_fault("slow_s")
        if slow:
            time.sleep(slow["slow_s"])
        if errors or warnings:
            record["status"] = 202
            self.finish_record(record)
            return self.answer(202, json.dumps({
                "message": "some or all payloads could not be processed or have warnings",
                "errors": errors, "warnings": warnings}), "application/json")
        record["status"] = 200
        self.finish_record(record)
        return self.answer(200, "^v^ telm logged")

    def listener(self, record, body):
        s = self.state
        record["points"] = [typed(body)]
        problem = None
        if not isinstance(body, dict):
            problem = "the body must be an object"
        else:
            for f in ["software_name", "software_version", "uploader_callsign"]:
                if not isinstance(body.get(f), str):
                    problem = f"{f} missing or not a string"
            u = body.get("uploader_position")
            if u is not None and not (isinstance(u, list) and len(u) == 3
                                      and all(is_number(x) for x in u)):
                problem = "uploader_position should be [lat, lon, alt] or null"
            if "mobile" in body and not isinstance(body["mobile"], bool):
                problem = "mobile should be a boolean"
        if problem:
            record["status"] = 400
            self.finish_record(record)
            return self.answer(400, problem)
        fault = s.take_fault("status")
        if fault:
            record["status"] = fault["status"]
            self.finish_record(record)
            return self.answer(fault["status"], "test fault")
        with s.lock:
            s.listeners.append(dict(body, received_at=time.time()))
        record["status"] = 200
        self.finish_record(record)
        return self.answer(200, "^v^ telm logged")


class Control(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"
    state = None
    api = None

    def log_message(self, *args):
        pass

    def answer(self, status, obj):
        data = json.dumps(obj).encode()
        self.send_response(status)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        self.wfile.write(data)

    def do_GET(self):
        with self.state.lock:
            return self.answer(200, {"requests": self.state.requests, "points": self.state.points,
                                     "listeners": self.state.listeners,
                                     "down": self.api.down})

    def do_POST(self):
        fault = json.loads(self.rfile.read(int(self.headers.get("Content-Length", "0"))))
        if "down_s" in fault:
            self.api.go_down(float(fault["down_s"]))
        else:
            with self.state.lock:
                self.state.faults.append(fault)
        return self.answer(200, {"ok": True})


class ApiServer:
    """The API's server on a fixed port, which can be taken down and brought back."""

    def __init__(self, state):
        self.state = state
        self.port = 0
        self.down = False
        self.server = None
        self.start()

    def start(self):
        handler = type("H", (Api,), {"state": self.state})
        ThreadingHTTPServer.allow_reuse_address = True
        self.server = ThreadingHTTPServer(("127.0.0.1", self.port), handler)
        self.server.daemon_threads = True
        self.port = self.server.server_address[1]
        threading.Thread(target=self.server.serve_forever, daemon=True).start()
        self.down = False

    def go_down(self, seconds):
        def cycle():
            self.down = True
            self.server.shutdown()
            self.server.server_close()
            time.sleep(seconds)
            self.start()
        threading.Thread(target=cycle, daemon=True).start()


def main():
    window_s = 86400.0
    args = sys.argv[1:]
    if "--window-s" in args:
        window_s = float(args[args.index("--window-s") + 1])
    state = State(window_s)
    api = ApiServer(state)
    handler = type("C", (Control,), {"state": state, "api": api})
    control = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    control.daemon_threads = True
    threading.Thread(target=control.serve_forever, daemon=True).start()
    print(json.dumps({"api": api.port, "control": control.server_address[1]}), flush=True)
    # Until the test that started it goes away (its end of stdin closes) or kills it.
    sys.stdin.read()


if __name__ == "__main__":
    main()
