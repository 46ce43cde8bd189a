"""An independent reader of stx recordings: the `mcap` package from PyPI (pinned, see
tests/record/python_mcap.rs). Prints what it finds as JSON on stdout; the Rust test compares.

    read_mcap.py summary FILE   whole file: summary, metadata, every message (indexed reader)
    read_mcap.py stream FILE    any file, cut or not: messages per topic (stream reader)
"""

import base64
import json
import sys
from collections import Counter
from importlib.metadata import version

from mcap.reader import make_reader
from mcap.records import Channel, Message
from mcap.stream_reader import StreamReader


def summary(path):
    with open(path, "rb") as f:
        reader = make_reader(f)
        s = reader.get_summary()
        stats = s.statistics
        channels = []
        for cid, ch in sorted(s.channels.items()):
            schema = s.schemas[ch.schema_id]
            channels.append({
                "topic": ch.topic,
                "schema_name": schema.name,
                "schema_encoding": schema.encoding,
                "message_encoding": ch.message_encoding,
                "count": stats.channel_message_counts.get(cid, 0),
            })
        metadata = [{"name": m.name, "metadata": m.metadata} for m in reader.iter_metadata()]
        seen = Counter()
        missing = []
        first_frame = None
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            seen[channel.topic] += 1
            body = json.loads(message.data)
            # Every field the message's JSON Schema requires is there.
            required = json.loads(schema.data).get("required", [])
            missing += [f"{channel.topic}.{k}" for k in required if k not in body]
            if schema.name == "stx.MavlinkFrame" and first_frame is None:
                first_frame = base64.b64decode(body["data"]).hex()
        print(json.dumps({
            "version": version("mcap"),
            "message_count": stats.message_count,
            "channels": channels,
            "metadata": metadata,
            "read": dict(seen),
            "missing_fields": missing,
            "first_frame_hex": first_frame,
        }))


def stream(path):
    topics = {}
    seen = Counter()
    error = None
    with open(path, "rb") as f:
        try:
            for record in StreamReader(f).records:
                if isinstance(record, Channel):
                    topics[record.id] = record.topic
                elif isinstance(record, Message):
                    seen[topics[record.channel_id]] += 1
        except Exception as e:  # a cut file ends in an error: report it, keep the count
            error = f"{type(e).__name__}: {e}"
    print(json.dumps({"version": version("mcap"), "read": dict(seen), "error": error}))


if __name__ == "__main__":
    {"summary": summary, "stream": stream}[sys.argv[1]](sys.argv[2])
