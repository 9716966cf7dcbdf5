#!/usr/bin/env python3
"""accelcal's MCAP reader against the specification's own examples (issue 20).

MCAP's conformance suite (foxglove/mcap, tests/conformance/data, MIT licence: data/mcap-conformance)
describes each example file as the records a reader must find, with the CRC-32 of its data
section. This script writes each example's bytes from that description, record by record as the
specification lays them out (independently of accelcal's writer), checks that they are the
example's own (the data section's CRC-32 is the one the description gives), then asks
`accelcal inspect --json` what the file holds: its topics, types and message counts must be the
description's. The examples cover padded records (fields a newer writer adds, which a reader
skips), chunks with message indexes, schemaless channels, attachments and metadata.

Usage: mcap_spec_test.py ACCELCAL DATA_DIR WORKDIR
"""
import glob
import json
import os
import shutil
import struct
import subprocess
import sys
import zlib

MAGIC = b"\x89MCAP0\r\n"
PAD = b"\x01\xff\xff"  # what the conformance writer appends to a record that may grow


def u16(v):
    return struct.pack("<H", int(v))


def u32(v):
    return struct.pack("<I", int(v))


def u64(v):
    return struct.pack("<Q", int(v))


def string(s):
    b = s.encode()
    return u32(len(b)) + b


def str_map(m):
    body = b"".join(string(k) + string(v) for k, v in m.items())
    return u32(len(body)) + body


def record(op, content):
    return bytes([op]) + u64(len(content)) + content


def content_of(rec, pad):
    """A record's content as the specification lays it out ('pad': with the bytes a newer
    writer may add)."""
    f = dict(rec["fields"])
    t = rec["type"]
    extra = PAD if pad else b""
    if t == "Header":
        return 0x01, string(f["profile"]) + string(f["library"]) + extra
    if t == "Schema":
        data = bytes(int(x) for x in f["data"])
        return 0x03, (u16(f["id"]) + string(f["name"]) + string(f["encoding"]) + u32(len(data)) +
                      data + extra)
    if t == "Channel":
        return 0x04, (u16(f["id"]) + u16(f["schema_id"]) + string(f["topic"]) +
                      string(f["message_encoding"]) + str_map(f["metadata"]) + extra)
    if t == "Message":  # cannot grow: its data is the rest
        return 0x05, (u16(f["channel_id"]) + u32(f["sequence"]) + u64(f["log_time"]) +
                      u64(f["publish_time"]) + bytes(int(x) for x in f["data"]))
    if t == "Attachment":
        data = bytes(int(x) for x in f["data"])
        body = (u64(f["log_time"]) + u64(f["create_time"]) + string(f["name"]) +
                string(f["media_type"]) + u64(len(data)) + data)
        return 0x09, body + u32(zlib.crc32(body)) + extra
    if t == "Metadata":
        return 0x0C, string(f["name"]) + str_map(f["metadata"]) + extra
    raise ValueError(t)


def example_bytes(doc):
    """The example's magic and data section up to its Data End, and Data End's CRC as given."""
    features = set(doc["meta"]["variant"]["features"])
    pad, chunked, indexed = "pad" in features, "ch" in features, "mx" in features
    out = bytearray(MAGIC)
    chunk = bytearray()
    index = {}  # channel -> [(log time, offset in chunk)]
    times = []
    given_crc = None
    for rec in doc["records"]:
        t = rec["type"]
        if t == "DataEnd":
            given_crc = int(dict(rec["fields"])["data_section_crc"])
            break
        op, content = content_of(rec, pad and not (chunked and t in ("Schema", "Channel")))
        if chunked and t in ("Schema", "Channel", "Message"):
            if t == "Message":
                f = dict(rec["fields"])
                index.setdefault(int(f["channel_id"]), []).append((int(f["log_time"]), len(chunk)))
                times.append(int(f["log_time"]))
            chunk += record(op, content)
        else:
            out += record(op, content)
    if chunked:
        body = (u64(min(times, default=0)) + u64(max(times, default=0)) + u64(len(chunk)) +
                u32(zlib.crc32(chunk)) + string("") + u64(len(chunk)) + bytes(chunk))
        out += record(0x06, body)
        if indexed:
            for channel, entries in index.items():
                pairs = b"".join(u64(t) + u64(o) for t, o in entries)
                out += record(0x07, u16(channel) + u32(len(pairs)) + pairs + PAD * pad)
    return bytes(out), given_crc


def main():
    accelcal, data, work = sys.argv[1], sys.argv[2], sys.argv[3]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    failures = []
    examples = sorted(glob.glob(os.path.join(data, "mcap-conformance", "*.json")))
    if len(examples) < 8:
        failures.append(f"the examples are missing: {examples}")
    for path in examples:
        name = os.path.basename(path)[:-5]
        with open(path) as f:
            doc = json.load(f)
        section, given = example_bytes(doc)
        if zlib.crc32(section) != given:
            failures.append(f"{name}: the bytes written are not the example's (CRC-32 "
                            f"{zlib.crc32(section)}, the example's {given})")
            continue
        # The file: the example's data section, then Data End, a Footer without summary, magic.
        whole = (section + record(0x0F, u32(given)) + record(0x02, u64(0) + u64(0) + u32(0)) +
                 MAGIC)
        mcap = os.path.join(work, name + ".mcap")
        with open(mcap, "wb") as f:
            f.write(whole)
        p = subprocess.run([accelcal, "inspect", "--json", mcap], capture_output=True, text=True)
        if p.returncode != 0:
            failures.append(f"{name}: inspect failed: {p.stderr}")
            continue
        got = json.loads(p.stdout)
        # What the description holds: each channel's topic, its schema's name, its messages.
        schemas = {dict(r["fields"])["id"]: dict(r["fields"])["name"]
                   for r in doc["records"] if r["type"] == "Schema"}
        want = {}
        channels = {}
        for r in doc["records"]:
            f = dict(r["fields"])
            if r["type"] == "Channel" and f["id"] not in channels:
                channels[f["id"]] = f["topic"]
                want[f["topic"]] = [schemas.get(f["schema_id"], "(no schema)"), 0]
            if r["type"] == "Message":
                want[channels[f["channel_id"]]][1] += 1
        have = {s["topic"]: [s["type"], s["samples"]] for s in got["streams"]}
        if have != want or got["truncated"] is not None:
            failures.append(f"{name}: read {have} (truncated: {got['truncated']}), the example "
                            f"holds {want}")
        # Cut anywhere, the file is read up to the cut with a warning, or refused with a reason.
        for cut in range(len(MAGIC), len(whole), max(1, len(whole) // 17)):
            with open(mcap, "wb") as f:
                f.write(whole[:cut])
            p = subprocess.run([accelcal, "inspect", "--json", mcap], capture_output=True,
                               text=True)
            if p.returncode not in (0, 3) or (p.returncode == 0 and
                                              json.loads(p.stdout)["truncated"] is None):
                failures.append(f"{name} cut at {cut}: exit {p.returncode}, {p.stdout[:200]}"
                                f"{p.stderr}")
        print(f"{name}: {have}")
    for failure in failures:
        print("FAIL:", failure)
    if failures:
        sys.exit(1)
    print(f"mcap examples: all {len(examples)} read as the specification describes them")


if __name__ == "__main__":
    main()
