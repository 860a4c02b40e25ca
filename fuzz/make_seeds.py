#!/usr/bin/python3
"""Writes the committed seed corpora of the libFuzzer targets (fuzz/corpus/).

Each seed is encoded the way the target's FuzzedDataProvider reads it:
integers from the end of the input (most significant byte consumed first),
strings and the remaining bytes from the front (see the comment at the top of
each fuzz/<target>_fuzzer.cpp).

  /usr/bin/python3 fuzz/make_seeds.py --bag SIM.bag --gt SIM_gt.tum --sim-yaml SIM.yaml

SIM.* come from `rvlio simulate --duration 0.3 --set lidar.columns=512 --out D
--name s` (a real simulated Ouster message; the other layouts re-encode its
points). Needs the Debian python3-rosbag package; only used to refresh seeds.
"""
import argparse
import os
import struct

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.path.join(ROOT, "fuzz", "corpus")

# Field names the pointcloud2 target picks by index (kNames).
NAMES = ["x", "y", "z", "intensity", "ring", "t", "time", "timestamp", "offset_time", "line",
         "tag", "reflectivity", "ambient", "range"]
# sensor_msgs/PointField datatypes.
INT8, UINT8, INT16, UINT16, INT32, UINT32, FLOAT32, FLOAT64 = range(1, 9)
FMT = {INT8: "b", UINT8: "B", INT16: "h", UINT16: "H", INT32: "i", UINT32: "I", FLOAT32: "f",
       FLOAT64: "d"}


class Provider:
    """Builds an input that FuzzedDataProvider reads back as the given values."""

    def __init__(self):
        self.front = bytearray()
        self.tail = bytearray()  # in consumption order (read from the end)

    def integral(self, value, lo, hi, type_bytes):
        span = hi - lo
        count, shift = 0, 0
        while shift < type_bytes * 8 and (span >> shift) > 0:
            count += 1
            shift += 8
        raw = (value - lo) % (1 << (8 * type_bytes))
        assert 0 <= value - lo <= span
        self.tail += raw.to_bytes(count, "big")

    def boolean(self, b):
        self.integral(1 if b else 0, 0, 255, 1)

    def string(self, s):
        data = s.encode() if isinstance(s, str) else s
        self.front += data.replace(b"\\", b"\\\\") + b"\\\n"

    def rest(self, data):
        self.front += data

    def build(self):
        return bytes(self.front) + bytes(reversed(self.tail))


def write(target, name, data):
    os.makedirs(os.path.join(CORPUS, target), exist_ok=True)
    with open(os.path.join(CORPUS, target, name), "wb") as f:
        f.write(data)


# ---------------------------------------------------------------- pointcloud2

def cloud_seed(points, fields, point_step, stamp_ns, type_index=0, stamp_index=0,
               bigendian=False, height=1):
    """points: list of dicts name -> value; fields: (name, offset, datatype)."""
    order = ">" if bigendian else "<"
    width = len(points) // height
    rows = []
    for p in points[:width * height]:
        buf = bytearray(point_step)
        for name, offset, dt in fields:
            struct.pack_into(order + FMT[dt], buf, offset, p.get(name, 0))
        rows.append(bytes(buf))
    fdp = Provider()
    fdp.integral(type_index, 0, 5, 4)
    fdp.integral(stamp_index, 0, 2, 4)
    fdp.integral(50, 0, 1000, 4)        # min_range 0.5 m
    fdp.integral(9950, 1, 100000, 4)    # max_range 100 m
    fdp.integral(stamp_ns, -(1 << 63), (1 << 63) - 1, 8)
    fdp.boolean(bigendian)
    fdp.boolean(False)                  # explicit geometry
    fdp.integral(len(fields), 0, 12, 4)
    for name, offset, dt in fields:
        if name in NAMES:
            fdp.integral(NAMES.index(name), 0, 255, 1)
        else:
            fdp.integral(255, 0, 255, 1)
            fdp.string(name)
        fdp.integral(offset, 0, 2**32 - 1, 4)
        fdp.integral(dt, 0, 255, 1)
        fdp.integral(1, 0, 2**32 - 1, 4)
    for v in (height, width, point_step, point_step * width):
        fdp.integral(v, 0, 2**32 - 1, 4)
    fdp.rest(b"".join(rows))
    return fdp.build()


def real_ouster(bag_path):
    import rosbag  # Debian python3-rosbag
    with rosbag.Bag(bag_path) as bag:
        for _, msg, _ in bag.read_messages():
            if msg._type == "sensor_msgs/PointCloud2":
                return msg
    raise SystemExit("no PointCloud2 in " + bag_path)


def decode_points(msg, rows, cols):
    fields = [(f.name, f.offset, f.datatype) for f in msg.fields]
    out = []
    for r in rows:
        for c in range(cols):
            base = r * msg.row_step + c * msg.point_step
            out.append({name: struct.unpack_from("<" + FMT[dt], msg.data, base + off)[0]
                        for name, off, dt in fields})
    return fields, out


def pointcloud2_seeds(bag_path):
    msg = real_ouster(bag_path)
    stamp = msg.header.stamp.secs * 10**9 + msg.header.stamp.nsecs
    fields, pts = decode_points(msg, rows=[8, 20], cols=24)
    write("pointcloud2", "ouster_sim", cloud_seed(pts, fields, msg.point_step, stamp, height=2))
    write("pointcloud2", "ouster_sim_bigendian",
          cloud_seed(pts, fields, msg.point_step, stamp, type_index=1, bigendian=True, height=2))
    t_end = max(p["t"] for p in pts)
    velodyne = [dict(p, time=(p["t"] - t_end) * 1e-9) for p in pts]  # stamp at the scan end
    write("pointcloud2", "velodyne_stamp_end",
          cloud_seed(velodyne, [("x", 0, FLOAT32), ("y", 4, FLOAT32), ("z", 8, FLOAT32),
                                ("intensity", 12, FLOAT32), ("ring", 16, UINT16),
                                ("time", 18, FLOAT32)], 22, stamp + t_end, stamp_index=0))
    hesai = [dict(p, timestamp=(stamp + p["t"]) * 1e-9) for p in pts]
    write("pointcloud2", "hesai_absolute_s",
          cloud_seed(hesai, [("x", 0, FLOAT32), ("y", 4, FLOAT32), ("z", 8, FLOAT32),
                             ("intensity", 12, FLOAT32), ("ring", 16, UINT16),
                             ("timestamp", 18, FLOAT64)], 26, stamp, type_index=3))
    livox = [dict(p, timestamp=float(stamp + p["t"]), tag=0, line=p["ring"] % 6) for p in pts]
    write("pointcloud2", "livox_absolute_ns",
          cloud_seed(livox, [("x", 0, FLOAT32), ("y", 4, FLOAT32), ("z", 8, FLOAT32),
                             ("intensity", 12, FLOAT32), ("tag", 16, UINT8), ("line", 17, UINT8),
                             ("timestamp", 18, FLOAT64)], 26, stamp))
    livox_rel = [dict(p, offset_time=p["t"]) for p in pts]
    write("pointcloud2", "livox_offset_time",
          cloud_seed(livox_rel, [("x", 0, FLOAT32), ("y", 4, FLOAT32), ("z", 8, FLOAT32),
                                 ("offset_time", 12, UINT32)], 16, stamp, type_index=4,
                     stamp_index=1))
    write("pointcloud2", "no_time_field",
          cloud_seed(pts[:4], [("x", 0, FLOAT32), ("y", 4, FLOAT32), ("z", 8, FLOAT32)], 12,
                     stamp))


# --------------------------------------------------------------------- config

def config_seed(yaml_text, overrides=()):
    fdp = Provider()
    fdp.integral(len(overrides), 0, 4, 4)
    for o in overrides:
        fdp.string(o)
    fdp.rest(yaml_text)
    return fdp.build()


def config_seeds(sim_yaml):
    def read(path):
        with open(path, "rb") as f:
            return f.read()
    write("config", "default_yaml", config_seed(read(os.path.join(ROOT, "config", "default.yaml"))))
    write("config", "paper_sim_yaml_with_overrides",
          config_seed(read(os.path.join(ROOT, "config", "paper_sim.yaml")),
                      ["rv.eps0=0.3", "extrinsics.imu_T_lidar.translation=[0.1,0,0.05]",
                       "backend=smoother"]))
    write("config", "simulated_sensor_yaml", config_seed(read(sim_yaml), ["lidar.type=ouster"]))
    # Inputs of bugs the fuzzer found (fixed; test/formats/fuzzregress).
    write("config", "recursive_alias", config_seed(b"a: &x [*x]\n"))
    bomb = ["a0: &a0 [1,1,1,1,1,1,1,1,1,1]"]
    for i in range(1, 6):
        bomb.append("a%d: &a%d [%s]" % (i, i, ",".join(["*a%d" % (i - 1)] * 10)))
    write("config", "alias_expansion", config_seed(("\n".join(bomb) + "\n").encode()))


# ----------------------------------------------------------------- trajectory

def trajectory_seed(mode, text, rate_pick=80, times=None):
    fdp = Provider()
    fdp.integral(mode, 0, 3, 4)
    if mode == 2:
        fdp.string(times)
    if mode in (1, 3):
        fdp.integral(rate_pick, 0, 255, 1)
    fdp.rest(text.encode())
    return fdp.build()


def kitti_line(x, y, z, qx, qy, qz, qw):
    r = [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
         [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
         [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]
    t = [x, y, z]
    return " ".join("%.6e %.6e %.6e %.6e" % (r[i][0], r[i][1], r[i][2], t[i]) for i in range(3))


def trajectory_seeds(gt_tum):
    with open(os.path.join(ROOT, "test", "data", "evo", "freiburg1_xyz-groundtruth.txt")) as f:
        tum = "".join(f.readlines()[:16])
    write("trajectory", "tum_freiburg1_xyz", trajectory_seed(0, tum))
    with open(gt_tum) as f:
        sim = "".join(f.readlines()[:12])
    write("trajectory", "tum_simulated_gt", trajectory_seed(3, sim))
    rows, stamps = [], []
    for line in tum.splitlines():
        if line.startswith("#"):
            continue
        v = [float(s) for s in line.split()]
        n = sum(q * q for q in v[4:8]) ** 0.5
        rows.append(kitti_line(v[1], v[2], v[3], *(q / n for q in v[4:8])))
        stamps.append(line.split()[0])
    kitti = "\n".join(rows) + "\n"
    write("trajectory", "kitti_10hz", trajectory_seed(1, kitti))
    write("trajectory", "kitti_with_times", trajectory_seed(2, kitti, times="\n".join(stamps) + "\n"))
    write("trajectory", "kitti_detected", trajectory_seed(3, kitti))
    # Inputs of bugs the fuzzer found (fixed; test/formats/fuzzregress).
    write("trajectory", "tum_huge_quaternion", trajectory_seed(0, "0 0 0 0 1e200 1e200 1e200 1e200\n"))
    write("trajectory", "kitti_tiny_rate", trajectory_seed(1, kitti, rate_pick=4))


def cut_pcap(path, limit):
    """The pcap file header and its first records, about `limit` bytes."""
    data = open(path, "rb").read()
    off = keep = 24
    while off + 16 <= len(data):
        incl = struct.unpack("<I", data[off + 8:off + 12])[0]
        if off + 16 + incl - 24 > limit and keep > 24:
            break
        off += 16 + incl
        keep = off
    return data[:keep]


def ouster_seeds():
    """Byte 0 picks the sensor (bits 0-2 profile: 0 RNG15, 1 RNG19, 2 FUSA,
    3 LEGACY; bits 3-4 beams: 0 -> 128, 1 -> 32), then the first packets of
    the real captures in test/data/ouster."""
    src = os.path.join(ROOT, "test", "data", "ouster")
    seeds = {"lb_rng15_128": (0, "OS-1-128_v2.3.0_1024x10_lb_n3.pcap", 40000),
             "rng19_128": (1, "OS-2-128-U1_v2.3.0_1024x10.pcap", 60000),
             "fusa_128": (2, "OS-1-128_767798045_1024x10_20230712_120049.pcap", 40000),
             "legacy_32": (3 | 1 << 3, "OS-1-32-G_v2.1.1_1024x10.pcap", 30000),
             "crc_rng15_128": (0, "crc_test.pcap", 30000),
             "imu_only": (0, "imu_zm_no_lidar.pcap", 6000)}
    for name, (pick, capture, limit) in seeds.items():
        write("ouster", name, bytes([pick]) + cut_pcap(os.path.join(src, capture), limit))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bag", required=True)
    ap.add_argument("--gt", required=True)
    ap.add_argument("--sim-yaml", required=True)
    a = ap.parse_args()
    pointcloud2_seeds(a.bag)
    config_seeds(a.sim_yaml)
    trajectory_seeds(a.gt)
    ouster_seeds()


if __name__ == "__main__":
    main()
