"""The chase cars' datagrams of a running station, held against horusdemodlib (PyPI), the
Horus tools' own sender of PAYLOAD_SUMMARY.

Usage: chase_horus.py PORT SECONDS. Listens on 127.0.0.1:PORT for the station's datagrams
until it has three of the payload and one of the predicted landing (or SECONDS pass), then asks
horusdemodlib's `send_payload_summary` to send the first payload datagram's point, capturing
the bytes it would put on the network (its socket's `sendto`, nothing sent), and prints one
JSON object: {"stx": [datagrams as received], "horus": the datagram horusdemodlib made}.
"""

import json
import socket
import sys
import time

from horusdemodlib import horusudp


def listen(port, seconds):
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", port))
    sock.settimeout(0.5)
    got = []
    end = time.time() + seconds
    while time.time() < end:
        try:
            data, _ = sock.recvfrom(65536)
        except socket.timeout:
            continue
        got.append(json.loads(data.decode("ascii")))
        payloads = [g for g in got if not g["callsign"].endswith("_LANDING")]
        landings = [g for g in got if g["callsign"].endswith("_LANDING")]
        if len(payloads) >= 3 and landings:
            break
    return got


def horus_of(point):
    """What horusdemodlib sends for `point` (a dict as Horus telemetry has it)."""
    sent = []

    class Capture(socket.socket):
        def sendto(self, data, *args):
            sent.append(data)
            return len(data)

    real = socket.socket
    horusudp.socket.socket = Capture
    try:
        horusudp.send_payload_summary(point, port=9, comment=point["comment"])
    finally:
        horusudp.socket.socket = real
    return json.loads(sent[0].decode("ascii")) if sent else None


def main():
    port, seconds = int(sys.argv[1]), float(sys.argv[2])
    got = listen(port, seconds)
    payloads = [g for g in got if not g["callsign"].endswith("_LANDING")]
    horus = None
    if payloads:
        p = payloads[0]
        horus = horus_of({
            "callsign": p["callsign"], "latitude": p["latitude"], "longitude": p["longitude"],
            "altitude": p["altitude"], "time": p["time"], "speed": p["speed"],
            "satellites": p["sats"], "battery_voltage": p["batt_voltage"], "comment": p["comment"],
        })
    print(json.dumps({"stx": got, "horus": horus}))


if __name__ == "__main__":
    main()
