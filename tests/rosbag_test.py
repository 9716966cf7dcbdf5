#!/usr/bin/env python3
"""ROS 1 bags written by ROS's own writer (Debian's python3-rosbag), read by accelcal (issue 20).

A simulated session (accelcal simulate --raw) is written as sensor_msgs/Imu messages in bags with
uncompressed, bz2 and lz4 chunks, beside Temperature and MagneticField topics, and as CSV: the
calibration from each bag is the calibration from the CSV, byte for byte (less the input's name
and digest). Then the ways a bag goes wrong: a recorder killed before it closed the bag (no index,
its last chunk open), a bag cut short, a corrupt chunk, a topic chosen that accelcal does not
know the fields of, and the topic and its fields as `inspect` lists them.

Usage: rosbag_test.py ACCELCAL WORKDIR
"""
import json
import os
import random
import shutil
import sys

import rosbag
import rospy
from sensor_msgs.msg import Imu, MagneticField, Temperature

from log_test_support import Checks, calibration, simulated_session


T0_S = 1_700_000_000  # the bags' first stamp [s], a time of 2023 as a live recording has


def write_bag(path, rows, compression, close=True, t0_s=T0_S):
    """The rows as /imu/data (sensor_msgs/Imu, stamped at their time from t0), with a
    temperature at 1/10 the rate and a magnetometer, as a ROS driver would publish them."""
    bag = rosbag.Bag(path, "w", compression=compression)
    gyro = random.Random(7)
    for i, (t_us, x, y, z) in enumerate(rows):
        stamp = rospy.Time(t0_s + t_us // 1_000_000, (t_us % 1_000_000) * 1000)
        m = Imu()
        m.header.seq = i
        m.header.stamp = stamp
        m.header.frame_id = "imu_link"
        m.orientation_covariance[0] = -1  # REP 145: no orientation
        m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z = x, y, z
        # The gyroscope at rest: white noise of 1 mrad/s on each axis, known from its seed.
        m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z = (
            gyro.gauss(0, 1e-3) for _ in range(3))
        bag.write("/imu/data", m, t=stamp)
        if i % 10 == 0:
            temperature = Temperature()
            temperature.header.stamp = stamp
            temperature.temperature = 25.0 + 1e-4 * i
            bag.write("/imu/temperature", temperature, t=stamp)
            mag = MagneticField()
            mag.header.stamp = stamp
            mag.magnetic_field.x = 2e-5
            bag.write("/imu/mag", mag, t=stamp)
    if close:
        bag.close()
    else:
        # A recorder killed: what it wrote is on disk, the bag never closed (no index).
        bag._file.flush()
        os.fsync(bag._file.fileno())


def main():
    accelcal, work = sys.argv[1], sys.argv[2]
    ck = Checks(accelcal)
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    p = lambda name: os.path.join(work, name)  # noqa: E731

    rows, want = simulated_session(ck, work, T0_S * 1_000_000)  # stamped as in the bags

    # Every chunk compression ROS writes: the same calibration.
    for compression in ("none", "bz2", "lz4"):
        bag = p(f"s_{compression}.bag")
        write_bag(bag, rows, compression)
        r = ck.run("calibrate", bag, "-o", p(f"{compression}.json"))
        ck.check(r.returncode == 0 and calibration(p(f"{compression}.json")) == want,
              f"the {compression} bag calibrates as its samples as CSV")
        ck.check("sensor_msgs/Imu" in r.stdout or "/imu/data" in r.stdout,
              f"the {compression} bag's summary names the topic read:\n{r.stdout}")

    # inspect: the topics, their types, what accelcal reads from them.
    r = ck.run("inspect", p("s_lz4.bag"), "--json")
    doc = json.loads(r.stdout)
    streams = {s["topic"]: s for s in doc["streams"]}
    ck.check(doc["format"] == "rosbag", "inspect says the format")
    ck.check(streams["/imu/data"]["type"] == "sensor_msgs/Imu" and
          streams["/imu/data"]["samples"] == len(rows) and
          streams["/imu/data"]["sensors"] == ["accelerometer", "gyroscope"],
          f"inspect lists the IMU topic: {streams.get('/imu/data')}")
    ck.check(streams["/imu/temperature"]["type"] == "sensor_msgs/Temperature" and
          streams["/imu/temperature"]["samples"] == (len(rows) + 9) // 10,
          "inspect lists the temperature topic")
    ck.check("linear_acceleration.x" in doc["fields"]["/imu/data"] and
          "temperature" in doc["fields"]["/imu/temperature"] and
          "magnetic_field.z" in doc["fields"]["/imu/mag"],
          "inspect lists each topic's fields")

    # A topic accelcal does not know the fields of: the error says to name them; named, read.
    r = ck.run("calibrate", p("s_none.bag"), "--topic", "/imu/mag", "-o", p("x.json"), expect=3)
    ck.check("name them with --columns" in r.stderr, f"unknown fields: {r.stderr}")
    r = ck.run("calibrate", p("s_none.bag"), "--topic", "/imu/data", "--columns",
            "linear_acceleration.x,linear_acceleration.y,linear_acceleration.z",
            "-o", p("named.json"))
    ck.check(calibration(p("named.json")) == want, "the fields named by --columns read the same")
    # A ROS stamp is a time by specification: another time unit is refused.
    r = ck.run("calibrate", p("s_none.bag"), "--time-unit", "ms", "-o", p("x.json"), expect=3)
    ck.check("does not apply" in r.stderr, f"--time-unit on a stamp: {r.stderr}")
    # The gyroscope of the same messages: --gyro the same bag reads angular_velocity.
    r = ck.run("inspect", p("s_none.bag"))
    ck.check("accelerometer, gyroscope" in r.stdout, f"inspect text:\n{r.stdout}")
    r = ck.run("noise", p("s_none.bag"), "--gyro", p("s_none.bag"), "--still", "--json")
    # Written as 1 mrad/s per sample at 100 Hz: a white noise of 1e-4 rad/s/sqrt(Hz), within 4σ
    # of the fit's own uncertainty.
    for axis in json.loads(r.stdout)["gyroscope"]["axes"]:
        white = axis["terms"]["white"]
        ck.check(abs(white["value"] - 1e-4) < 4 * white["sigma"],
              f"the gyroscope's white noise from angular_velocity: {white}")

    # A recorder killed before it closed the bag: no index, the last chunk open. What it wrote is
    # read, as the same calibration (the chunks the writer had flushed hold every sample).
    write_bag(p("killed.bag"), rows, "none", close=False)
    r = ck.run("calibrate", p("killed.bag"), "-o", p("killed.json"), expect=None)
    # The writer may still hold the last chunk in memory: the samples flushed are a prefix.
    r = ck.run("inspect", p("killed.bag"), "--json")
    killed = {s["topic"]: s for s in json.loads(r.stdout)["streams"]}
    ck.check(0 < killed["/imu/data"]["samples"] <= len(rows), f"the killed bag reads: {killed}")

    # Cut short inside a chunk: an uncompressed chunk's whole messages are read, with a warning
    # naming where it stopped; a compressed chunk is lost whole, with a warning.
    with open(p("s_none.bag"), "rb") as f:
        data = f.read()
    for compression in ("none", "lz4"):
        with open(p(f"s_{compression}.bag"), "rb") as f:
            data = f.read()
        with open(p(f"cut_{compression}.bag"), "wb") as f:
            f.write(data[: len(data) * 3 // 5])
        r = ck.run("inspect", p(f"cut_{compression}.bag"), "--json")
        doc = json.loads(r.stdout)
        ck.check(doc["truncated"] and "ends inside a chunk" in doc["truncated"],
              f"the cut {compression} bag says where it stopped: {doc['truncated']}")
        n = {s["topic"]: s for s in doc["streams"]}["/imu/data"]["samples"]
        ck.check(0 < n < len(rows), f"the cut {compression} bag gives its whole messages: {n}")
        r = ck.run("noise", p(f"cut_{compression}.bag"), "--still", expect=None)
        ck.check("cut short" in r.stdout + r.stderr or "ends inside a chunk" in r.stdout + r.stderr,
              f"the cut {compression} bag warns when read:\n{r.stdout}{r.stderr}")

    # A corrupt compressed chunk: an error naming the byte.
    with open(p("s_bz2.bag"), "rb") as f:
        data = bytearray(f.read())
    at = data.find(b"BZh")
    data[at + 100] ^= 0x55
    with open(p("corrupt.bag"), "wb") as f:
        f.write(data)
    r = ck.run("calibrate", p("corrupt.bag"), "-o", p("x.json"), expect=3)
    ck.check("does not decompress" in r.stderr and "byte " in r.stderr,
          f"a corrupt chunk is named: {r.stderr}")

    # accelcal's own writer (simulate --format rosbag), read by ROS's reader: its index (message
    # count, chunks), its type's MD5, every stamp and reading the simulation's.
    ck.run("simulate", "--scenario", "yang2012", "--raw", "--duration", "20", "--format", "rosbag",
           "-o", p("sim.bag"))
    with rosbag.Bag(p("sim.bag")) as bag:
        info = bag.get_type_and_topic_info()
        ck.check(bag.get_message_count() == len(rows) and
                 info.msg_types == {"sensor_msgs/Imu": Imu._md5sum} and
                 info.topics["/imu/data"].message_count == len(rows),
                 f"ROS reads accelcal's bag's index: {bag.get_message_count()}, {info}")
        same = True
        for k, (_, msg, t) in enumerate(bag.read_messages()):
            t_us, x, y, z = rows[k]
            a = msg.linear_acceleration
            same = same and (msg.header.stamp.to_nsec() == t.to_nsec() == t_us * 1000 and
                             (a.x, a.y, a.z) == (x, y, z) and msg.header.seq == k)
        ck.check(same and k + 1 == len(rows), "ROS reads accelcal's bag as the simulation's samples")

    ck.finish("rosbag")


if __name__ == "__main__":
    main()
