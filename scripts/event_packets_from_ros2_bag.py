#!/usr/bin/env python3
"""Converts event_camera_msgs/EventPacket messages of a ROS 2 bag (SQLite .db3, CDR) into an
event packet file (format: docs/event_file_format.md#event-packet-files), the form the ROS-free
decoder tests read.

Usage: event_packets_from_ros2_bag.py BAG.db3 OUT.evpk [--first N] [--count N] [--topic T]
Only Python's standard library is used (no ROS 2 installation needed).
"""
import argparse
import sqlite3
import struct
import sys

MAGIC = b"EBSLAM-EVENT-PACKETS v1\n"


class CdrReader:
    """Little-endian CDR (the encapsulation header 00 01 is checked); alignment is relative to
    the first byte after the 4-byte encapsulation header."""

    def __init__(self, data):
        if len(data) < 4 or data[0:2] != b"\x00\x01":
            raise ValueError("not little-endian CDR")
        self.data = data
        self.pos = 4

    def align(self, n):
        rel = self.pos - 4
        self.pos += (-rel) % n

    def read(self, fmt, size):
        self.align(size)
        (value,) = struct.unpack_from("<" + fmt, self.data, self.pos)
        self.pos += size
        return value

    def string(self):
        n = self.read("I", 4)
        s = self.data[self.pos:self.pos + n]
        self.pos += n
        return s.rstrip(b"\x00").decode()

    def bytes(self):
        n = self.read("I", 4)
        b = self.data[self.pos:self.pos + n]
        if len(b) != n:
            raise ValueError("truncated byte sequence")
        self.pos += n
        return b


def parse_event_packet(data):
    r = CdrReader(data)
    sec = r.read("i", 4)
    nsec = r.read("I", 4)
    frame_id = r.string()
    height = r.read("I", 4)
    width = r.read("I", 4)
    seq = r.read("Q", 8)
    time_base = r.read("Q", 8)
    encoding = r.string()
    is_bigendian = r.read("B", 1)
    events = r.bytes()
    return dict(stamp_ns=sec * 1000000000 + nsec, frame_id=frame_id, height=height, width=width,
                seq=seq, time_base=time_base, encoding=encoding, is_bigendian=is_bigendian,
                events=events)


def read_bag(path, topic=None):
    db = sqlite3.connect("file:%s?mode=ro" % path, uri=True)
    topics = {tid: (name, typ) for tid, name, typ in db.execute("select id, name, type from topics")}
    for tid, data in db.execute("select topic_id, data from messages order by timestamp, id"):
        name, typ = topics[tid]
        if topic is not None and name != topic:
            continue
        if not typ.endswith("msg/EventPacket") and not typ.endswith("msg/EventArray"):
            continue
        yield parse_event_packet(bytes(data))


def write_packet(out, p):
    enc = p["encoding"].encode()
    frame = p["frame_id"].encode()
    out.write(struct.pack("<qIIQQB", p["stamp_ns"], p["width"], p["height"], p["seq"],
                          p["time_base"], p["is_bigendian"]))
    out.write(struct.pack("<H", len(enc)) + enc)
    out.write(struct.pack("<H", len(frame)) + frame)
    out.write(struct.pack("<I", len(p["events"])) + p["events"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bag")
    ap.add_argument("out")
    ap.add_argument("--first", type=int, default=0, help="index of the first packet to keep")
    ap.add_argument("--count", type=int, default=-1, help="packets to keep (-1: all)")
    ap.add_argument("--topic", default=None)
    a = ap.parse_args()
    packets = list(read_bag(a.bag, a.topic))
    end = len(packets) if a.count < 0 else a.first + a.count
    with open(a.out, "wb") as out:
        out.write(MAGIC)
        for p in packets[a.first:end]:
            write_packet(out, p)
    print("%d of %d packets written to %s" % (len(packets[a.first:end]), len(packets), a.out),
          file=sys.stderr)


if __name__ == "__main__":
    main()
