"""rvlio.evaluate reproduces every value evo printed (reference.json)."""
import json

import numpy as np
import pytest

import rvlio

TOL = 1e-6        # reference.json prints 6 decimals
SCALE_TOL = 1e-8  # the Sim3 scale is printed with 10


def count_numbers(j):
    if isinstance(j, bool):
        return 0
    if isinstance(j, (int, float)):
        return 1
    if isinstance(j, dict):
        return sum(count_numbers(v) for v in j.values())
    if isinstance(j, list):
        return sum(count_numbers(v) for v in j)
    return 0


def test_reproduces_every_value_of_reference_json(evo_dir):
    reference = json.loads((evo_dir / "reference.json").read_text())
    compared = 0

    def expect(expected, actual, tol=TOL):
        nonlocal compared
        assert actual == pytest.approx(expected, abs=tol)
        compared += 1

    def expect_stats(expected, stats):
        for key, value in expected.items():
            if key in ("rmse", "mean", "median", "std", "min", "max"):
                expect(value, stats[key])

    assert len(reference["cases"]) == 2
    for case in reference["cases"]:
        ref, est = evo_dir / case["ref"], evo_dir / case["est"]
        se3 = rvlio.evaluate(ref, est, align="se3")
        assert se3["align"] == "se3" and se3["warnings"] == []
        expect(case["matched"], se3["matched"], 0)
        expect_stats(case["ape_se3"], se3["ape"])
        rpe = case["rpe_trans_delta1_frames"]
        expect(rpe["pairs"], se3["rpe"]["pairs"], 0)
        expect_stats(rpe, se3["rpe"])
        if "ape_se3_angle_deg_rmse" in case:
            expect(case["ape_se3_angle_deg_rmse"], se3["ape_rot_deg"]["rmse"])
        if "rpe_angle_deg_delta1_rmse" in case:
            expect(case["rpe_angle_deg_delta1_rmse"], se3["rpe_rot_deg"]["rmse"])
        sim3 = rvlio.evaluate(str(ref), str(est), align="sim3")
        expect_stats(case["ape_sim3"], sim3["ape"])
        expect(case["ape_sim3"]["scale"], sim3["scale"], SCALE_TOL)
        if "ape_none" in case:
            expect_stats(case["ape_none"], rvlio.evaluate(ref, est, align="none")["ape"])
        if "rpe_trans_delta10_frames_rmse" in case:
            expect(case["rpe_trans_delta10_frames_rmse"],
                   rvlio.evaluate(ref, est, rpe_delta=10)["rpe"]["rmse"])
    assert compared == count_numbers(reference["cases"])


def test_arrays_give_the_same_numbers_as_files(evo_dir):
    case = json.loads((evo_dir / "reference.json").read_text())["cases"][0]
    ref, est = evo_dir / case["ref"], evo_dir / case["est"]
    from_files = rvlio.evaluate(ref, est)
    from_arrays = rvlio.evaluate(np.loadtxt(ref), np.loadtxt(est))
    assert from_arrays["matched"] == from_files["matched"]
    for key in ("rmse", "mean", "median", "std", "max"):
        assert from_arrays["ape"][key] == pytest.approx(from_files["ape"][key], abs=1e-9)
        assert from_arrays["rpe"][key] == pytest.approx(from_files["rpe"][key], abs=1e-9)


def test_bad_evaluation_arguments(evo_dir, tmp_path):
    case = json.loads((evo_dir / "reference.json").read_text())["cases"][0]
    ref = evo_dir / case["ref"]
    with pytest.raises(FileNotFoundError, match="est trajectory .*missing.tum' does not exist"):
        rvlio.evaluate(ref, tmp_path / "missing.tum")
    with pytest.raises(ValueError, match="align"):
        rvlio.evaluate(ref, ref, align="affine")
    with pytest.raises(ValueError, match=r"est must be a TUM file path or an \(N, 8\) array"):
        rvlio.evaluate(ref, np.zeros((5, 7)))
