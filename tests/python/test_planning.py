"""View planning from Python: the simulated run and its comparison on the same entry point as
`ctk plan` (same trajectory, same files), the files read back as objects, a run stopped by its
callback, the keywords' defaults equal to the library's, the rule drawing from a given picture,
and bad input refused by name."""
import inspect
import json
import os

import numpy as np
import pytest

import ctk
from ctk import _ctk

from conftest import run

# A small planner on a small detector: a few seconds per trajectory on 2 cores.
SMALL = dict(views=8, scout_nside=1, coarse_size=48, coarse_voxel_mm=2.0, binning=2, detector_shape=(360, 360),
             pitch_mm=1.2)


def test_plan_compares_trajectories_and_writes_what_the_command_line_writes(tmp_path, ctk_command):
    # A trajectory of one's own: the whole sphere's order as a direction list, so it must be
    # acquired and scored exactly as the whole sphere is (a lab of its own, the same noise).
    mine = tmp_path / "mine.json"
    ctk.write_directions(mine, "mine", ctk.planning_directions(8, "whole-sphere"))
    name, directions = ctk.read_directions(mine)
    assert name == "mine" and directions.shape == (768, 3)
    # A list written by Python's own json module, not by ctk: read alike, directions made unit length.
    other = tmp_path / "other.json"
    other.write_text(json.dumps({"format": "ctk-directions/1", "name": "by-hand", "directions": [[0, 0, 2], [3, 4, 0]]}))
    name, directions = ctk.read_directions(other)
    assert name == "by-hand"
    np.testing.assert_allclose(directions, [[0, 0, 1], [0.6, 0.8, 0]], rtol=0, atol=1e-15)
    result = ctk.plan(tmp_path / "py", phantoms=["sample-2"], compare=True, random_draws=2, eval_voxel_mm=2.4,
                      eval_iterations=3, compare_directions=[mine], **SMALL)
    assert not result.stopped
    assert list(result.trajectories) == ["planned", "whole-sphere", "random", "random-2", "mine"]
    figures = result.comparison["trajectories"]
    assert figures["mine"] == figures["whole-sphere"]
    assert figures["mine"] != figures["random"]
    planned = result.planned
    calibrated = [v for v in planned.views if v.get("calibrated")]
    assert len(calibrated) == 8
    assert planned.matrices.shape == (8, 3, 4)
    # The matrices are geometry.json's ok views, in order.
    geometry = ctk.read_geometry(planned.geometry_file)
    ok = [np.array(v["P"]).reshape(3, 4) for v in geometry["views"] if v.get("status", "ok") == "ok"]
    np.testing.assert_allclose(planned.matrices, np.array(ok), rtol=1e-12)
    assert ctk.read_plan(os.path.join(planned.folder, "trajectory.json"))["views"] == planned.views
    assert os.path.exists(planned.pictures[0]) and planned.pictures[0].endswith("plan-map.png")
    comparison = ctk.read_plan_comparison(tmp_path / "py" / "comparison.json")
    assert comparison["trajectories"] == result.comparison["trajectories"]
    for name in result.trajectories:
        figures = comparison["trajectories"][name]
        assert figures["views"] == 8 and figures["rmse_per_mm"] > 0
    assert comparison["random_draws"]["count"] == 2

    # The command line on the same settings asks for the same directions and calibrates alike.
    options = ["--views", "8", "--scout-nside", "1", "--coarse-size", "48", "--coarse-voxel", "2", "--binning", "2",
               "--cols", "360", "--rows", "360", "--pitch", "1.2"]
    run([ctk_command, "plan", "--out", str(tmp_path / "cli"), "--phantom", "sample-2", *options])
    cli = ctk.read_plan(tmp_path / "cli" / "planned" / "trajectory.json")
    assert [v["direction_holder"] for v in cli["views"]] == [v["direction_holder"] for v in planned.views]
    assert [v["status"] for v in cli["views"]] == [v["status"] for v in planned.views]
    assert cli["planner"] == planned.report["planner"]
    assert planned.report["planner"]["picture_median"] is True  # the default, recorded


def test_a_callback_returning_false_stops_the_plan(tmp_path):
    seen = []

    def callback(trajectory, record):
        seen.append((trajectory, record["request"]))
        return len(seen) < 3

    result = ctk.plan(tmp_path / "p", phantoms=["sample-2"], callback=callback, **SMALL)
    assert result.stopped and result.trajectories == {}
    assert seen == [("planned", 0), ("planned", 1), ("planned", 2)]
    assert not (tmp_path / "p" / "planned" / "trajectory.json").exists()


def test_the_keywords_default_to_the_librarys_settings():
    defaults = _ctk._plan_defaults()
    for function in (ctk.plan, ctk.plan_lab, ctk.plan_on_picture):
        checked = 0
        for name, parameter in inspect.signature(function).parameters.items():
            if name in defaults:
                assert parameter.default == defaults[name], (function.__name__, name)
                checked += 1
        assert checked >= 13, function.__name__


def test_the_rule_draws_from_a_given_picture_where_it_may():
    # An aluminium plate 4 mm thick in the x = 0 plane, on a small planner grid: its edges want
    # the directions in its plane, and the rule never asks for a direction out of reach.
    n, voxel = 48, 1.0
    centres = (np.arange(n) - (n - 1) / 2) * voxel
    z, y, x = np.meshgrid(centres, centres, centres, indexing="ij")
    plate = ((np.abs(x) <= 2) & (np.abs(y) <= 15) & (np.abs(z) <= 15)).astype(np.float32) * 0.07
    keywords = dict(views=40, coarse_size=n, coarse_voxel_mm=voxel, seed=2)
    below = lambda d: abs(d[2]) < 0.9  # noqa: E731
    planned = ctk.plan_on_picture(plate, reachable=below, **keywords)
    assert planned.shape == (40, 3)
    assert np.allclose(np.linalg.norm(planned, axis=1), 1) and np.all(np.abs(planned[:, 2]) < 0.9)
    even = ctk.plan_on_picture(plate, reachable=below, edge_tangency_weight=0, **keywords)
    in_plane = lambda d: int(np.sum(np.abs(d[:, 0]) < np.sin(np.radians(10))))  # noqa: E731
    assert in_plane(planned) >= in_plane(even) + 4
    assert np.array_equal(planned, ctk.plan_on_picture(plate, reachable=below, **keywords))
    with pytest.raises(ValueError, match=r"shape \(47, 48, 48\)"):
        ctk.plan_on_picture(plate[1:], **keywords)
    with pytest.raises(ValueError, match="PlanRequest.views"):
        ctk.plan_on_picture(plate, **{**keywords, "views": 1})


def test_bad_plans_are_refused_by_name(tmp_path):
    with pytest.raises(ValueError, match="PlanRequest.views"):
        ctk.plan(tmp_path / "a", phantoms=["sample-2"], views=1)
    with pytest.raises(ValueError, match="SimulatedPlanRequest.phantoms"):
        ctk.plan(tmp_path / "b", phantoms=[])
    with pytest.raises(ValueError, match="ComparisonOptions.voxel_mm"):
        ctk.plan(tmp_path / "c", phantoms=["sample-2"], eval_voxel_mm=0)
    with pytest.raises(ValueError, match="LabPlanRequest.timeout_s"):
        ctk.plan_lab(tmp_path, tmp_path / "scan.json", tmp_path / "out", timeout_s=0)
    reserved = tmp_path / "reserved.json"
    ctk.write_directions(reserved, "random-3", [[1, 0, 0]])
    with pytest.raises(ctk.InputError, match="'random-3' is a trajectory the comparison makes itself") as refused:
        ctk.plan(tmp_path / "e", phantoms=["sample-2"], compare=True, compare_directions=[reserved])
    assert refused.value.file == str(reserved) and refused.value.key == "name"
    with pytest.raises(ValueError, match="SimulatedPlanRequest.compare_directions"):
        ctk.plan(tmp_path / "f", phantoms=["sample-2"], compare_directions=[reserved])
    with pytest.raises(ctk.InputError) as missing:
        ctk.plan(tmp_path / "d", phantoms=["sample-2"], compare_only=True)
    assert "planned" in str(missing.value)
    assert not (tmp_path / "d" / "comparison.json").exists()

    # A lab's own folder as the output is refused before anything is asked for or written.
    ctk.plan(tmp_path / "setup", phantoms=["sample-2"], **{**SMALL, "views": 2})
    lab = tmp_path / "lab"
    lab.mkdir()
    with pytest.raises(ctk.InputError, match="out: "):
        ctk.plan_lab(lab, tmp_path / "setup" / "planned" / "scan.json", lab, views=5)
    assert list(lab.iterdir()) == []

    # Plan files are checked when read back.
    (tmp_path / "not-a-plan.json").write_text(json.dumps({"format": "ctk-diagnosis/1"}))
    with pytest.raises(ctk.InputError) as wrong:
        ctk.read_plan(tmp_path / "not-a-plan.json")
    assert wrong.value.key == "format"
    (tmp_path / "no-views.json").write_text(json.dumps({"format": "ctk-plan/1", "planner": {}}))
    with pytest.raises(ctk.InputError) as views:
        ctk.read_plan(tmp_path / "no-views.json")
    assert views.value.key == "views"
