#!/usr/bin/env python3
"""ROS 2 bags in SQLite (rosbag2's .db3), read by accelcal (issue 20).

A simulated session is written as rosbag2's SQLite storage lays it out (its `topics` and
`messages` tables; with and without the `message_definitions` table that rosbag2 has since
Iron), each sensor_msgs/msg/Imu message serialised here in CDR (independently of accelcal's
writer), beside a Temperature topic and a topic of a type accelcal cannot know. The calibration
from each bag is the one from its samples as CSV, byte for byte; the gyroscope's noise comes from
its angular_velocity; the bag is opened without a byte written beside it or in it. Then what goes
wrong: a topic whose definition the bag does not carry, a bag given through a pipe, a truncated
database, an SQLite database that is not a bag.

Usage: rosbag2_test.py ACCELCAL WORKDIR
"""
import hashlib
import json
import os
import random
import shutil
import sqlite3
import struct
import sys

import yaml

from log_test_support import Checks, calibration, simulated_session

T0_NS = 1_700_000_000 * 10**9  # a live recording's stamps


class Cdr:
    """CDR, little-endian, as ROS 2 serialises: each value aligned to its size from the start
    after the 4-byte encapsulation."""

    def __init__(self):
        self.body = bytearray()

    def put(self, fmt, value):
        size = struct.calcsize(fmt)
        self.body += b"\0" * (-len(self.body) % size)
        self.body += struct.pack("<" + fmt, value)

    def string(self, s):
        b = s.encode() + b"\0"
        self.put("I", len(b))
        self.body += b

    def bytes(self):
        return b"\x00\x01\x00\x00" + bytes(self.body)


def imu_message(t_ns, accel, gyro=None):
    """The CDR bytes; `gyro` None: no rates (angular_velocity_covariance[0] = -1, REP 145)."""
    m = Cdr()
    m.put("i", t_ns // 10**9)
    m.put("I", t_ns % 10**9)
    m.string("imu_link")
    for q in (0.0, 0.0, 0.0, 1.0):
        m.put("d", q)
    for i in range(9):
        m.put("d", -1.0 if i == 0 else 0.0)
    for v in gyro if gyro is not None else (0.0, 0.0, 0.0):
        m.put("d", v)
    for i in range(9):
        m.put("d", -1.0 if i == 0 and gyro is None else 0.0)
    for v in accel:
        m.put("d", v)
    for _ in range(9):
        m.put("d", 0.0)
    return m.bytes()


def temperature_message(t_ns, celsius):
    m = Cdr()
    m.put("i", t_ns // 10**9)
    m.put("I", t_ns % 10**9)
    m.string("imu_link")
    m.put("d", celsius)
    m.put("d", 0.0)
    return m.bytes()


IMU_DEFINITION = (
    "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\n"
    "float64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\n"
    "float64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\n"
    "float64[9] linear_acceleration_covariance\n" + "=" * 80 + "\nMSG: std_msgs/Header\n"
    "builtin_interfaces/Time stamp\nstring frame_id\n" + "=" * 80 +
    "\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n" + "=" * 80 +
    "\nMSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n" +
    "=" * 80 + "\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n")


def write_db3(path, rows, iron, wal_from=None, index=True):
    """rosbag2's SQLite storage: Humble's tables, and Iron's message_definitions when `iron`.
    `wal_from`: in WAL mode (rosbag2's resilient preset), its recorder killed after the rows from
    `wal_from` on were committed to the log and before any checkpoint (they are in FILE-wal only;
    FILE-shm is left too). `index`: with rosbag2's index of the messages' timestamps."""
    for old in (path, path + "-wal", path + "-shm"):
        if os.path.exists(old):
            os.remove(old)
    if wal_from is not None:
        pid = os.fork()
        if pid:
            os.waitpid(pid, 0)
            return
    db = sqlite3.connect(path)
    if wal_from is not None:
        db.execute("PRAGMA journal_mode=WAL")
        db.execute("PRAGMA wal_autocheckpoint=0")
    db.execute("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL)")
    db.execute("CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL,"
               " metadata TEXT NOT NULL)")
    db.execute("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,"
               " serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL)")
    db.execute("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,"
               " timestamp INTEGER NOT NULL, data BLOB NOT NULL)")
    if index:
        db.execute("CREATE INDEX timestamp_idx ON messages (timestamp ASC)")
    topics = [(1, "/imu/data", "sensor_msgs/msg/Imu"), (2, "/imu/temperature",
                                                        "sensor_msgs/msg/Temperature"),
              (3, "/vendor/status", "vendor_msgs/msg/Status")]
    for id_, name, type_ in topics:
        db.execute("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '')", (id_, name, type_))
    if iron:
        db.execute("CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT"
                   " NULL, encoding TEXT NOT NULL, encoded_message_definition TEXT NOT NULL,"
                   " type_description_hash TEXT NOT NULL)")
        db.execute("INSERT INTO message_definitions VALUES (1, 'sensor_msgs/msg/Imu', 'ros2msg',"
                   " ?, '')", (IMU_DEFINITION,))
    gyro = random.Random(7)
    for i, (t_us, x, y, z) in enumerate(rows):
        if i == wal_from:
            db.commit()
            db.execute("PRAGMA wal_checkpoint(TRUNCATE)")
        t_ns = T0_NS + t_us * 1000
        w = [gyro.gauss(0, 1e-3) for _ in range(3)]
        db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (1, ?, ?)",
                   (t_ns, imu_message(t_ns, (x, y, z), w)))
        if i % 10 == 0:
            db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (2, ?, ?)",
                       (t_ns, temperature_message(t_ns, 25.0)))
            db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (3, ?, ?)",
                       (t_ns, b"\x00\x01\x00\x00\x07\x00\x00\x00"))
    db.commit()
    if wal_from is not None:
        os._exit(0)  # killed: the log neither checkpointed nor removed
    db.close()


def digests(work):
    """Each file of `work` and its SHA-256."""
    return {n: hashlib.sha256(open(os.path.join(work, n), "rb").read()).hexdigest()
            for n in sorted(os.listdir(work))}


def hostile_schemas(ck, p, bag):
    """A bag whose tables are not tables: refused at once, naming the file and the reason (a view
    over a recursive query had run until the disk was full of SQLite's temporary files)."""
    endless = ("WITH RECURSIVE r(n) AS (SELECT 1 UNION ALL SELECT n + 1 FROM r) SELECT n AS id, 1 "
               "AS topic_id, -n AS timestamp, randomblob(100) AS data FROM r")
    cases = {
        "view-messages": ["DROP TABLE messages", "CREATE VIEW messages AS " + endless],
        "view-topics": ["DROP TABLE topics", "CREATE VIEW topics AS SELECT n AS id, 'x' AS name, "
                        "'y' AS type, 'cdr' AS serialization_format FROM (" + endless + ") "
                        "ORDER BY id DESC"],
        "view-definitions": ["DROP TABLE message_definitions",
                             "CREATE VIEW message_definitions AS SELECT 't' AS topic_type, 'e' AS "
                             "encoding, 'd' AS encoded_message_definition FROM (" + endless + ")"],
        "generated-data": ["DROP TABLE messages",
                           "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER, "
                           "timestamp INTEGER, data BLOB GENERATED ALWAYS AS "
                           "(zeroblob(100000000)) VIRTUAL)",
                           "INSERT INTO messages(topic_id, timestamp) VALUES (1, 1)"],
    }
    for case, statements in cases.items():
        path = p(f"{case}.db3")
        shutil.copy(bag, path)
        db = sqlite3.connect(path)
        for statement in statements:
            db.execute(statement)
        db.commit()
        db.close()
        for command in (["inspect", path], ["calibrate", path, "-o", p(f"{case}.json")]):
            r = ck.run(*command, expect=3, timeout=20)
            ck.check(r.stderr.startswith(f"accelcal: {path}: an SQLite database whose ") and
                     ("is a view, not a table" in r.stderr or "is computed" in r.stderr) and
                     not os.path.exists(p(f"{case}.json")),
                     f"{case}, {command[0]}: {r.stderr}")


def killed_recorder(ck, p, work, rows, want):
    """rosbag2's resilient preset (WAL) with its recorder killed: the last 40 % of the session in
    FILE-wal only. Read as committed, with nothing written in or beside the bag (no checkpoint
    into it, FILE-shm untouched, nothing created): it had read the database alone, the samples
    of its first 60 % with no warning."""
    os.makedirs(p("wal"))
    bag = os.path.join(p("wal"), "killed.db3")
    write_db3(bag, rows, True, wal_from=len(rows) * 6 // 10)
    before = digests(p("wal"))
    ck.check(sorted(before) == ["killed.db3", "killed.db3-shm", "killed.db3-wal"] and
             os.path.getsize(bag + "-wal") > 0, f"a killed recorder's files: {before}")
    r = ck.run("calibrate", bag, "-o", p("killed.json"))
    ck.check(r.returncode == 0 and calibration(p("killed.json")) == want,
             f"the killed recorder's bag calibrates as its samples as CSV: {r.stdout}{r.stderr}")
    doc = json.loads(ck.run("inspect", bag, "--json").stdout)
    streams = {s["topic"]: s for s in doc["streams"]}
    ck.check(streams["/imu/data"]["samples"] == len(rows),
             f"inspect counts the samples in the log: {doc['streams']}")
    ck.check(digests(p("wal")) == before, f"nothing written in or beside the bag: "
             f"{digests(p('wal'))}, before {before}")
    # A transaction the recorder never committed, and a frame torn by the kill: not applied (a
    # frame whose checksum does not follow ends the log, as SQLite reads it).
    with open(bag + "-wal", "ab") as f:
        f.write(bytes(random.Random(5).randrange(256) for _ in range(4096 + 24)))
    r = ck.run("calibrate", bag, "-o", p("torn.json"))
    ck.check(r.returncode == 0 and calibration(p("torn.json")) == want,
             f"a torn frame after the last commit is not applied: {r.stderr}")
    # A log that is not SQLite's: refused, naming it.
    with open(bag + "-wal", "r+b") as f:
        f.write(b"\0\0\0\0")
    r = ck.run("inspect", bag, expect=3)
    ck.check(r.stderr.startswith(f"accelcal: {bag}: its write-ahead log {bag}-wal is not one "
                                 "SQLite wrote"), f"a log that is not SQLite's: {r.stderr}")
    # An empty log (a checkpoint emptied it): the database alone, as without one.
    with open(bag + "-wal", "wb"):
        pass
    r = ck.run("inspect", bag, "--json")
    streams = {s["topic"]: s for s in json.loads(r.stdout)["streams"]}
    ck.check(streams["/imu/data"]["samples"] == len(rows) * 6 // 10,
             f"an empty log: the database's samples: {streams['/imu/data']}")


def main():
    accelcal, work = sys.argv[1], sys.argv[2]
    ck = Checks(accelcal)
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    p = lambda name: os.path.join(work, name)  # noqa: E731

    rows, want = simulated_session(ck, work, T0_NS // 1000)

    for iron in (False, True):
        name = "iron" if iron else "humble"
        bag = p(f"{name}.db3")
        write_db3(bag, rows, iron)
        before = hashlib.sha256(open(bag, "rb").read()).hexdigest()
        listing = sorted(os.listdir(work))
        r = ck.run("calibrate", bag, "-o", p(f"{name}.json"))
        ck.check(r.returncode == 0 and calibration(p(f"{name}.json")) == want,
              f"the {name} bag calibrates as its samples as CSV")
        ck.check("a ROS 2 bag (SQLite): /imu/data" in r.stdout, f"the summary:\n{r.stdout}")
        ck.check(hashlib.sha256(open(bag, "rb").read()).hexdigest() == before and
              sorted(os.listdir(work)) == sorted(listing + [f"{name}.json"]),
              f"the {name} bag is read without a byte written in or beside it: "
              f"{sorted(os.listdir(work))}")
        doc = json.loads(ck.run("inspect", bag, "--json").stdout)
        streams = {s["topic"]: s for s in doc["streams"]}
        ck.check(doc["format"] == "db3" and streams["/imu/data"]["samples"] == len(rows) and
              streams["/imu/data"]["sensors"] == ["accelerometer", "gyroscope"] and
              streams["/imu/temperature"]["samples"] == (len(rows) + 9) // 10 and
              "temperature" in doc["fields"]["/imu/temperature"] and
              doc["fields"]["/vendor/status"] == [],
              f"inspect of the {name} bag: {doc['streams']}")
        r = ck.run("noise", bag, "--gyro", bag, "--still", "--json")
        for axis in json.loads(r.stdout)["gyroscope"]["axes"]:
            white = axis["terms"]["white"]
            ck.check(abs(white["value"] - 1e-4) < 4 * white["sigma"],
                  f"the gyroscope's white noise from the {name} bag: {white}")
        # A topic whose definition the bag does not carry: said, not guessed.
        r = ck.run("calibrate", bag, "--topic", "/vendor/status", "--columns", "1,2,3",
                "-o", p("x.json"), expect=3)
        ck.check("does not carry its definition" in r.stderr, f"an unknown type: {r.stderr}")

    killed_recorder(ck, p, work, rows, want)
    hostile_schemas(ck, p, p("iron.db3"))
    # Without rosbag2's index of the timestamps, the messages are still read in their order
    # (their times and ids sorted here; SQLite would sort the rows with their data, in temporary
    # files, which the VFS does not make), and the ids of equal times in theirs.
    write_db3(p("no-index.db3"), rows, True, index=False)
    db = sqlite3.connect(p("no-index.db3"))  # and 48 MB more than SQLite's cache could sort
    for k in range(48):
        db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (3, ?, ?)",
                   (T0_NS + k * 10**9 + 1, bytes(1 << 20)))
    db.commit()
    db.close()
    r = ck.run("calibrate", p("no-index.db3"), "-o", p("no-index.json"))
    ck.check(r.returncode == 0 and calibration(p("no-index.json")) == want,
             f"a bag without the index of timestamps calibrates the same: {r.stderr}")

    # Through a pipe, a database cannot be opened: said.
    with open(p("iron.db3"), "rb") as f:
        r = ck.run("calibrate", "-", "-o", p("x.json"), expect=3, stdin=f)
    ck.check("read from its file" in r.stderr, f"a bag through a pipe: {r.stderr}")
    # A truncated database: SQLite's reason, no crash, nothing written.
    with open(p("iron.db3"), "rb") as f:
        data = f.read()
    with open(p("cut.db3"), "wb") as f:
        f.write(data[: len(data) // 2])
    r = ck.run("calibrate", p("cut.db3"), "-o", p("cut.json"), expect=3)
    ck.check("SQLite" in r.stderr and not os.path.exists(p("cut.json")),
          f"a truncated database: {r.stderr}")
    # An SQLite database that is not a bag.
    db = sqlite3.connect(p("other.db3"))
    db.execute("CREATE TABLE things(a)")
    db.commit()
    db.close()
    r = ck.run("inspect", p("other.db3"), expect=3)
    ck.check("not a ROS 2 bag" in r.stderr, f"another database: {r.stderr}")

    # accelcal's own writer (simulate --format db3), read by SQLite and decoded here: Iron's
    # tables, the topic and its definition, every stamp and reading the simulation's.
    ck.run("simulate", "--scenario", "yang2012", "--raw", "--duration", "20", "--format", "db3",
           "-o", p("sim.db3"))
    db = sqlite3.connect(p("sim.db3"))
    ck.check(db.execute("SELECT * FROM schema").fetchall() == [(4, "iron")] and
             db.execute("SELECT name, type, serialization_format FROM topics").fetchall() ==
             [("/imu/data", "sensor_msgs/msg/Imu", "cdr")] and
             db.execute("SELECT topic_type, encoding FROM message_definitions").fetchall() ==
             [("sensor_msgs/msg/Imu", "ros2msg")] and
             "message_count: %d" % len(rows) in db.execute("SELECT metadata FROM metadata")
             .fetchone()[0], "accelcal's bag has rosbag2's tables")
    # Each message the bytes this script's own CDR encoder gives (simulate writes no rates).
    stored = db.execute("SELECT timestamp, data FROM messages ORDER BY id").fetchall()
    same = all(t_ns == t_us * 1000 and data == imu_message(t_ns, (x, y, z))
               for (t_ns, data), (t_us, x, y, z) in zip(stored, rows))
    db.close()
    ck.check(same and len(stored) == len(rows), "accelcal's bag holds the simulation's samples")

    # Any file name reads back from the metadata's YAML as itself (quoted).
    odd = p("odd: name #1.db3")
    ck.run("simulate", "--scenario", "yang2012", "--raw", "--duration", "1", "--format", "db3",
           "-o", odd)
    db = sqlite3.connect(odd)
    meta = yaml.safe_load(db.execute("SELECT metadata FROM metadata").fetchone()[0])
    db.close()
    info = meta["rosbag2_bagfile_information"]
    ck.check(info["relative_file_paths"] == ["odd: name #1.db3"] and
             info["files"][0]["path"] == "odd: name #1.db3" and
             info["topics_with_message_count"][0]["topic_metadata"]["name"] == "/imu/data",
             f"the metadata names the file: {info}")

    ck.finish("rosbag2 sqlite")


if __name__ == "__main__":
    main()
