"""rvlio.evaluate_map against an independent computation (scipy's cKDTree and
numpy plane fits), the command line's JSON, and bad input."""
import json

import numpy as np
import pytest
from scipy.spatial import cKDTree

import rvlio

from conftest import run_cli

D = 0.1        # max_distance
K = 8          # num_neighbors
RADIUS = 0.5   # search_radius
TOL = 1e-6


def scene(seed=1):
    """A box corner (floor and two walls, so some neighbourhoods are edges),
    a 2 cm noisy map of it with a few far outliers; float32-exact values, as
    rvlio searches in single precision."""
    rng = np.random.default_rng(seed)

    def box(n, noise):
        u = rng.uniform(0.0, 3.0, (n, 2))
        face = rng.integers(0, 3, n)
        p = np.zeros((n, 3))
        p[face == 0] = np.c_[u[face == 0], np.zeros((face == 0).sum())]
        p[face == 1] = np.c_[u[face == 1, 0], np.zeros((face == 1).sum()), u[face == 1, 1]]
        p[face == 2] = np.c_[np.zeros((face == 2).sum()), u[face == 2]]
        return p + rng.normal(0.0, noise, p.shape)

    ref = box(30000, 0.001)
    ref = ref[ref[:, 0] > 0.5]  # the wall x = 0 and a strip were not surveyed
    mp = np.vstack([box(4000, 0.02), rng.uniform(-1.0, 4.0, (50, 3))])
    return mp.astype(np.float32).astype(np.float64), ref.astype(np.float32).astype(np.float64)


def plane_distances(mp, ref):
    """|point-to-plane| (NaN without a valid plane) and nearest distance (NaN
    beyond the search radius), with rvlio's validity test."""
    tree = cKDTree(ref)
    dist, idx = tree.query(mp, k=K, distance_upper_bound=RADIUS)
    nearest = np.where(np.isfinite(dist[:, 0]), dist[:, 0], np.nan)
    plane = np.full(len(mp), np.nan)
    full = np.isfinite(dist).all(axis=1)
    for i in np.flatnonzero(full):
        pts = ref[idx[i]]
        c = pts.mean(axis=0)
        cov = (pts - c).T @ (pts - c) / K
        w, v = np.linalg.eigh(cov)  # ascending
        n = v[:, 0]
        if w[2] < 1e-18 or w[1] < 0.1 * w[2] or w[0] > 0.1 * w[1]:
            continue
        if np.abs((pts - c) @ n).max() > 0.1:
            continue
        plane[i] = abs(n @ (mp[i] - c))
    return plane, nearest


def stats(x):
    return {"count": len(x), "mean": x.mean(), "rms": np.sqrt((x ** 2).mean()),
            "median": np.median(x), "p95": np.percentile(x, 95), "max": x.max()}


def independent(mp, ref):
    plane, nearest = plane_distances(mp, ref)
    inlier = nearest <= D
    d_ref, _ = cKDTree(mp).query(ref, k=1, distance_upper_bound=D)
    covered = np.isfinite(d_ref)
    chamfer = 0.5 * (np.where(inlier, nearest, D).mean() + np.where(covered, d_ref, D).mean())
    with_plane = inlier & np.isfinite(plane)
    return {"accuracy": stats(plane[with_plane]), "nearest": stats(nearest[inlier]),
            "completeness": covered.mean(), "chamfer": chamfer,
            "outlier_fraction": 1.0 - inlier.mean(), "inliers": int(inlier.sum()),
            "no_plane": int((inlier & ~np.isfinite(plane)).sum())}


def test_matches_ckdtree_and_numpy_plane_fits():
    mp, ref = scene()
    got = rvlio.evaluate_map(mp, ref, max_distance=D, num_neighbors=K, search_radius=RADIUS)
    want = independent(mp, ref)
    assert got["no_plane"] > 0 and got["outlier_fraction"] > 0  # the scene has both
    assert got["inliers"] == want["inliers"]
    assert got["no_plane"] == want["no_plane"]
    for key in ("accuracy", "nearest"):
        for stat, value in want[key].items():
            assert got[key][stat] == pytest.approx(value, abs=TOL), (key, stat)
    for key in ("completeness", "chamfer", "outlier_fraction"):
        assert got[key] == pytest.approx(want[key], abs=TOL), key


def write_pcd(path, points):
    header = ("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
              f"WIDTH {len(points)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
              f"POINTS {len(points)}\nDATA binary\n")
    path.write_bytes(header.encode() + points.astype("<f4").tobytes())


def test_paths_arrays_and_the_command_line_agree(tmp_path, rvlio_bin):
    mp, ref = scene(2)
    write_pcd(tmp_path / "map.pcd", mp)
    write_pcd(tmp_path / "ref.pcd", ref)
    from_arrays = rvlio.evaluate_map(mp, ref)
    from_paths = rvlio.evaluate_map(tmp_path / "map.pcd", str(tmp_path / "ref.pcd"))
    cli = json.loads(run_cli(rvlio_bin, "eval", "--map", tmp_path / "map.pcd",
                             "--ref-map", tmp_path / "ref.pcd", "--json").stdout)
    for key in ("completeness", "chamfer", "outlier_fraction"):
        assert from_paths[key] == from_arrays[key]
        assert cli[key] == pytest.approx(from_arrays[key], rel=1e-9)
    for stat in ("mean", "rms", "median", "p95", "max"):
        assert cli["accuracy"][stat] == pytest.approx(from_arrays["accuracy"][stat], rel=1e-9)
    assert len(cli["profile"]) == len(from_arrays["profile"]["chainage"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["map.pcd", "ref.pcd"]  # read only


def test_clouds_in_a_national_grid_give_the_figures_of_clouds_near_zero():
    """Shifted to a UTM easting and northing (beyond float32's millimetres
    and the search structure's key reach), both clouds are evaluated in the
    reference's local frame: the same figures, the axis shifted back."""
    mp, ref = scene(4)
    near = rvlio.evaluate_map(mp, ref)
    shift = np.array([500000.0, 5400000.0, 0.0])
    far = rvlio.evaluate_map(mp + shift, ref + shift)
    assert far["inliers"] == near["inliers"]
    for key in ("completeness", "chamfer", "outlier_fraction"):
        assert far[key] == pytest.approx(near[key], abs=TOL), key
    for stat in ("mean", "rms", "median", "p95", "max"):
        assert far["accuracy"][stat] == pytest.approx(near["accuracy"][stat], abs=TOL), stat
    assert np.asarray(far["axis"]["origin"]) - shift == pytest.approx(near["axis"]["origin"], abs=TOL)


def test_bad_input_raises_value_error(tmp_path):
    mp, ref = scene(3)
    with pytest.raises(ValueError, match="do not overlap"):
        rvlio.evaluate_map(mp + 1000.0, ref)
    bad = mp.copy()
    bad[5, 1] = np.nan
    with pytest.raises(ValueError, match="1 of"):
        rvlio.evaluate_map(bad, ref)
    with pytest.raises(ValueError, match="no points"):
        rvlio.evaluate_map(np.zeros((0, 3)), ref)
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        rvlio.evaluate_map(np.zeros((4, 2)), ref)
    (tmp_path / "empty.pcd").write_text("")
    with pytest.raises(ValueError, match="empty.pcd"):
        rvlio.evaluate_map(tmp_path / "empty.pcd", ref)
    with pytest.raises(FileNotFoundError):
        rvlio.evaluate_map(tmp_path / "missing.pcd", ref)
