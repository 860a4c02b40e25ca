"""rvlio.read_bag on Ouster packet recordings: a real capture with its
metadata JSON (found next to it, or given as lidar.ouster_metadata) and the
ROS1 packet bag the Ouster driver records (test/data/ouster)."""
import os

import numpy as np

import rvlio

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "test", "data", "ouster")


def kinds(path, config=None):
    reader = rvlio.read_bag(path, config)
    messages = list(reader)
    return messages, reader.lidar_layout


def test_capture_with_metadata_next_to_it():
    messages, layout = kinds(os.path.join(DATA, "OS-1-128_v2.3.0_1024x10_lb_n3.pcap"))
    assert layout == "ouster_packets"
    scans = [m for m in messages if m.kind == "scan"]
    imu = [m for m in messages if m.kind == "imu"]
    assert len(scans) == 3
    assert len(imu) == 30
    acc = np.mean([np.linalg.norm(s.acc) for s in imu])
    assert abs(acc - 9.81) < 0.15 * 9.81
    for s in scans:
        assert len(s) > 50000
        assert np.all(np.diff(np.unique(s.times)) > 0)
        assert 0.09 < (s.t_end_ns - s.t_ns) * 1e-9 < 0.11


def test_metadata_from_the_configuration(tmp_path):
    capture = os.path.join(DATA, "crc_test.pcap")
    config = rvlio.Config.load(set={"lidar.ouster_metadata": os.path.join(DATA, "crc_test.json")})
    messages, _ = kinds(capture, config)
    assert any(m.kind == "scan" for m in messages)
    assert sum(m.kind == "imu" for m in messages) == 10


def test_ros1_packet_bag():
    messages, layout = kinds(os.path.join(DATA, "512x10_raw.bag"))
    assert layout == "ouster_packets"
    assert sum(m.kind == "scan" for m in messages) == 1
    assert sum(m.kind == "imu" for m in messages) == 10


def test_imu_only_capture_of_firmware_3_2():
    # ACCEL32_GYRO32_NMEA IMU packets (8 x 8 measurements, SI units), no lidar
    # packets: IMU samples and no scans.
    messages, layout = kinds(os.path.join(DATA, "imu_zm_no_lidar.pcap"))
    assert layout == "ouster_packets"
    assert not any(m.kind == "scan" for m in messages)
    imu = [m for m in messages if m.kind == "imu"]
    assert len(imu) == 64
    acc = np.mean([np.linalg.norm(s.acc) for s in imu])
    assert abs(acc - 9.81) < 0.15 * 9.81
    assert np.all(np.diff([s.t_ns for s in imu]) > 0)
