"""The Python module against known answers: the crane lift in the plant (robots/) and the Panda in a
MotionBenchMaker bookshelf (shared data), the command line's verdicts, planned paths re-checked
edge by edge, the error matrix, and several Python threads on one checker."""
import os
import subprocess
import threading
import time

import numpy as np
import pytest

from conftest import SOURCE

CRANE_COORDINATES = ["base_x", "base_y", "base_yaw", "slew", "luff", "telescope_1", "hoist"]


def random_states(problem, n, seed):
    """n configurations drawn uniformly within the problem's limits."""
    rng = np.random.default_rng(seed)
    return rng.uniform(problem.lower, problem.upper, size=(n, problem.dof))


def line(a, b, steps):
    t = np.linspace(0.0, 1.0, steps)[:, None]
    return (1 - t) * a + t * b


# ---- the crane ------------------------------------------------------------------------------

def test_crane_problem_tells_its_coordinates_limits_start_and_goal(crane):
    assert crane.dof == 7
    assert crane.coordinate_names == CRANE_COORDINATES
    assert crane.lower.shape == crane.upper.shape == (7,)
    assert np.all(crane.lower <= crane.upper)
    # robots/sites/plant_lift.yaml: slew from -pi/2 to pi/2, telescope 5 -> 8.5 m
    np.testing.assert_allclose(crane.start[3:6], [-1.570796326795, 0.834431313317, 5.0])
    np.testing.assert_allclose(crane.goal[3:6], [1.570796326795, 0.71942438464, 8.5])
    assert "load" in crane.components and "tank_1" in crane.objects


def test_crane_start_and_goal_are_valid_with_the_lift_clearance_but_not_with_half_a_metre(rc, crane, crane_checker):
    ends = np.stack([crane.start, crane.goal])
    valid = crane_checker.check(ends)
    assert valid.dtype == np.bool_ and valid.shape == (2,)
    assert valid.all()
    assert rc.Checker(crane, padding=0.25, threads=1).check(ends).all()
    # The skid hangs 0.3 m above its support (robots/sites/README.md).
    assert not rc.Checker(crane, padding=0.5, threads=1).check(ends).any()
    assert crane_checker.contacts(crane.start) == []


def test_crane_straight_line_swings_the_load_into_tank_1(crane, crane_checker):
    states = line(crane.start, crane.goal, 101)
    valid = crane_checker.check(states)
    first = int(np.argmin(valid))
    assert not valid[first], "the straight line from pick to set-down is expected to collide"
    assert 0.2 < first / 100 < 0.35
    contacts = crane_checker.contacts(states[first])
    assert {(c["kind"], c["component"], c["object"]) for c in contacts} >= {("environment", "load", "tank_1")}
    for contact in contacts:
        assert len(contact["point"]) == 3 and isinstance(contact["triangle"], int) and contact["description"]
    # One list per row for a batch; empty exactly where check() says valid (safe mode).
    per_state = crane_checker.contacts(states[::10])
    assert [not c for c in per_state] == list(valid[::10])


def test_crane_distance_is_zero_exactly_where_the_lift_collides_and_its_points_that_far_apart(rc, crane, crane_checker):
    states = line(crane.start, crane.goal, 41)
    answer = crane_checker.distance(states)
    distance, points = answer["distance"], answer["points"]
    assert distance.shape == (41,) and points.shape == (41, 2, 3)
    assert len(answer["component"]) == 41 and len(answer["other"]) == 41
    # Safe mode without padding is exact: a state is valid exactly when its distance is positive.
    assert np.array_equal(distance > 0, crane_checker.check(states))
    assert np.allclose(np.linalg.norm(points[:, 0] - points[:, 1], axis=1), distance, atol=1e-9)
    # The skid hangs 0.3 m above its support at the start (robots/sites/README.md).
    assert 0.25 < distance[0] <= 0.3 + 1e-9
    # The bounded form: the distance where it is below the bound, else the bound itself.
    capped = crane_checker.distance(states, upper_bound=0.1)["distance"]
    assert np.array_equal(capped, np.minimum(distance, 0.1))
    assert crane_checker.distance(crane.start)["distance"].shape == (1,)
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="upperBound"):
            crane_checker.distance(states, upper_bound=bad)


def test_crane_penetration_depth_is_measured_where_the_lift_collides(crane, crane_checker):
    states = line(crane.start, crane.goal, 41)
    assert "penetration_depth" not in crane_checker.distance(states)
    answer = crane_checker.distance(states, penetration=True)
    depth, lower, direction = (answer["penetration_depth"], answer["penetration_lower_bound"],
                               answer["penetration_direction"])
    assert depth.shape == lower.shape == (41,) and direction.shape == (41, 3)
    colliding = answer["distance"] <= 0
    assert colliding.any() and not colliding.all()
    # Measured exactly on the colliding states: the hulls' depth, at least the lower bound.
    assert np.array_equal(np.isnan(depth), ~colliding) and np.array_equal(np.isnan(lower), ~colliding)
    assert np.all(depth[colliding] >= lower[colliding]) and np.all(lower[colliding] >= 0)
    moving = colliding & (depth > 0)
    assert np.allclose(np.linalg.norm(direction[moving], axis=1), 1.0)


def test_crane_straight_edge_is_rejected_certified_and_discrete(crane, crane_checker):
    assert crane_checker.check_motions(crane.start, crane.goal).tolist() == [False]
    valid, last_valid = crane_checker.check_motions(crane.start, crane.goal, certified=False)
    assert valid.tolist() == [False]
    # The edge is straight in the state space, where the slew (a continuous joint) turns the
    # shorter way: here, by pi, the other way round than the line above; it collides as well.
    assert 0.0 < last_valid[0] < 1.0
    # Standing still at a valid state is a valid edge, in both kinds.
    assert crane_checker.check_motions(crane.start, crane.start).tolist() == [True]
    valid, last_valid = crane_checker.check_motions(crane.start, crane.start, certified=False)
    assert valid.tolist() == [True] and last_valid.tolist() == [1.0]


def test_out_of_limits_state_is_invalid(crane, crane_checker):
    q = crane.start.copy()
    q[CRANE_COORDINATES.index("telescope_1")] = crane.upper[5] + 1.0
    assert crane_checker.check(q).tolist() == [False]
    assert [c["kind"] for c in crane_checker.contacts(q)] == ["out_of_bounds"]


# ---- the Panda ------------------------------------------------------------------------------

POST = """world:
  collision_objects:
    - id: post
      primitives:
        - type: box
          dimensions: [0.1, 0.1, 0.1]
      primitive_poses:
        - position: [{x}, 0, 0.5]
          orientation: [0, 0, 0, 1]
"""


def test_panda_upright_hits_a_post_around_its_forearm_and_misses_one_beside_it(rc, panda_dir, tmp_path):
    verdicts = {}
    for x in (0.0, 1.5):
        scene = tmp_path / f"post_{x}.yaml"
        scene.write_text(POST.format(x=x))
        problem = rc.load(panda_dir / "panda.urdf", srdf=panda_dir / "panda.srdf", scene=scene)
        checker = rc.Checker(problem, threads=1)
        upright = problem.neutral
        verdicts[x] = checker.check(upright)[0]
        contacts = checker.contacts(upright)
        assert bool(contacts) != verdicts[x]
        assert all(c["object"] == "post" for c in contacts)
    assert verdicts == {0.0: False, 1.5: True}


def test_panda_verdicts_equal_the_command_line_on_the_same_csv(bookshelf, panda_checker, panda_dir, tmp_path):
    states = random_states(bookshelf, 600, seed=29)
    states[:2] = [bookshelf.start, bookshelf.goal]
    csv = tmp_path / "states.csv"
    np.savetxt(csv, states, delimiter=",", header=",".join(bookshelf.coordinate_names), comments="", fmt="%.17g")
    out = tmp_path / "verdicts.csv"
    scenario = panda_dir / "problems" / "bookshelf_small_panda"
    subprocess.run([os.environ.get("RASTERCHECK_CLI", "rastercheck"), "check", "--robot", panda_dir / "panda.urdf",
                    "--srdf", panda_dir / "panda.srdf", "--scene", scenario / "scene0001.yaml", "--states", csv,
                    "--out", out, "--threads", "1"], check=True, capture_output=True)
    cli = np.loadtxt(out, delimiter=",", skiprows=1, usecols=0, dtype=int).astype(bool)
    valid = panda_checker.check(states)
    assert valid[:2].all()  # MotionBenchMaker's start and goal are valid
    assert 0 < valid.sum() < len(valid)
    np.testing.assert_array_equal(valid, cli)


def test_other_real_dtypes_and_layouts_give_the_float64_verdicts(bookshelf, panda_checker):
    states = random_states(bookshelf, 64, seed=3).astype(np.float32).astype(np.float64)
    expected = panda_checker.check(states)
    np.testing.assert_array_equal(panda_checker.check(states.astype(np.float32)), expected)
    np.testing.assert_array_equal(panda_checker.check(np.asfortranarray(states)), expected)
    np.testing.assert_array_equal(panda_checker.check(np.repeat(states, 2, axis=0)[::2]), expected)
    np.testing.assert_array_equal(panda_checker.check(states.tolist()), expected)
    assert panda_checker.check(np.empty((0, bookshelf.dof))).shape == (0,)


def test_planned_path_is_valid_edge_by_edge_and_densely(rc, bookshelf, panda_checker):
    path, result = rc.plan(bookshelf, time_limit=5.0, seed=1, threads=1)
    assert result.solved, result
    assert result.states_checked > 0 and result.time > 0
    assert path.ndim == 2 and path.shape[1] == bookshelf.dof and len(path) >= 2
    np.testing.assert_allclose(path[0], bookshelf.start, atol=1e-9)
    np.testing.assert_allclose(path[-1], bookshelf.goal, atol=1e-9)
    assert panda_checker.check_motions(path[:-1], path[1:]).all()
    dense = np.concatenate([line(a, b, 200) for a, b in zip(path[:-1], path[1:])])
    assert rc.Checker(bookshelf, mode="exact", threads=1).check(dense).all()
    # The same seed plans the same path.
    again, _ = rc.plan(bookshelf, time_limit=5.0, seed=1, threads=1)
    np.testing.assert_array_equal(again, path)


def test_plan_takes_a_start_and_goal_and_a_planner_by_name(rc, crane):
    start = crane.start.copy()
    goal = start.copy()
    goal[CRANE_COORDINATES.index("hoist")] = 9.0  # lift the skid 6.8 m straight up
    path, result = rc.plan(crane, start=start, goal=goal, planner="rrtconnect", time_limit=5.0, seed=2,
                           simplify=False, threads=1)
    assert result.solved and result.planner == "RRTConnect"
    np.testing.assert_allclose(path[[0, -1]], [start, goal], atol=1e-9)


# ---- an OMPL.app problem --------------------------------------------------------------------

def box_obj(name, center, half):
    """A closed box as Wavefront OBJ text: 8 corners, 12 outward triangles."""
    corners = [[c + s * h for c, s, h in zip(center, signs, half)]
               for signs in [(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1),
                             (-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)]]
    faces = [(1, 3, 2), (1, 4, 3), (5, 6, 7), (5, 7, 8), (1, 2, 6), (1, 6, 5),
             (2, 3, 7), (2, 7, 6), (3, 4, 8), (3, 8, 7), (4, 1, 5), (4, 5, 8)]
    return f"o {name}\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in corners) + \
        "".join(f"f {a} {b} {c}\n" for a, b, c in faces)


def test_omplapp_cube_goes_around_a_wall(rc, tmp_path):
    (tmp_path / "cube.obj").write_text(box_obj("cube", (0, 0, 0), (0.5, 0.5, 0.5)))
    (tmp_path / "wall.obj").write_text(box_obj("wall", (3, 0, 0), (0.25, 1.5, 1.5)))
    ends = "".join(f"{which}.{key} = {value}\n" for which, x in (("start", 0), ("goal", 6))
                   for key, value in (("x", x), ("y", 0), ("z", 0), ("theta", 0), ("axis.x", 1), ("axis.y", 0),
                                      ("axis.z", 0)))
    volume = "".join(f"volume.{bound}.{axis} = {value}\n" for bound, values in (("min", (-2, -4, -4)), ("max", (8, 4, 4)))
                     for axis, value in zip("xyz", values))
    cfg = tmp_path / "wall.cfg"
    cfg.write_text(f"[problem]\nname = wall\nrobot = cube.obj\nworld = wall.obj\n{ends}{volume}")
    problem = rc.load_cfg(cfg)
    assert problem.name == "wall" and problem.objects == ["wall"]
    assert problem.coordinate_names == ["x", "y", "z", "qx", "qy", "qz", "qw"]
    np.testing.assert_allclose(problem.start, [0, 0, 0, 0, 0, 0, 1])
    np.testing.assert_allclose(problem.goal, [6, 0, 0, 0, 0, 0, 1])
    np.testing.assert_allclose(problem.lower[:3], [-2, -4, -4])
    checker = rc.Checker(problem, threads=1)
    through = problem.start.copy()
    through[0] = 3.0
    assert checker.check([problem.start, problem.goal, through]).tolist() == [True, True, False]
    assert [c["object"] for c in checker.contacts(through)] == ["wall"]
    assert checker.check_motions(problem.start, problem.goal).tolist() == [False]
    path, result = rc.plan(problem, planner="rrtconnect", time_limit=5.0, seed=3, threads=1)
    assert result.solved
    assert checker.check_motions(path[:-1], path[1:]).all()


# ---- errors ---------------------------------------------------------------------------------

def test_loader_errors_become_file_not_found_and_value_errors(rc, tmp_path):
    with pytest.raises(FileNotFoundError, match="no_such_robot.urdf"):
        rc.load(tmp_path / "no_such_robot.urdf")
    with pytest.raises(FileNotFoundError, match="no_such_problem.cfg"):
        rc.load_cfg(str(tmp_path / "no_such_problem.cfg"))
    broken = tmp_path / "broken.urdf"
    broken.write_text("<robot name='r'><link name='a'/><joint name='j' type='revolute'>")
    with pytest.raises(ValueError, match="broken.urdf"):
        rc.load(broken)
    with pytest.raises(TypeError):
        rc.load(42)
    for none in (lambda: rc.Checker(None), lambda: rc.plan(None)):
        with pytest.raises(TypeError):
            none()


def test_options_shapes_dtypes_and_non_finite_values_are_value_errors(rc, crane, crane_checker):
    for options in ({"mode": "fast"}, {"padding": -1.0}, {"padding": float("nan")}, {"backend": "tpu"},
                    {"threads": -1}):
        with pytest.raises(ValueError):
            rc.Checker(crane, **options)
    for q in (np.zeros(6), np.zeros((3, 8)), np.zeros((2, 3, 7)), np.zeros(()), None, "q",
              np.zeros((2, 7), dtype=complex), np.array([[object()] * 7]), np.zeros((2, 7), dtype=bool)):
        with pytest.raises(ValueError, match=r"q "):
            crane_checker.check(q)
    states = np.tile(crane.start, (4, 1))
    states[2, 4] = np.nan
    with pytest.raises(ValueError, match=r"row 2: coordinate 4 \('luff'\)"):
        crane_checker.check(states)
    states[2, 4] = np.inf
    with pytest.raises(ValueError, match="row 2"):
        crane_checker.contacts(states)
    with pytest.raises(ValueError, match=r"same shape, not \(2, 7\) and \(1, 7\)"):
        crane_checker.check_motions(states[:2], states[:1])
    with pytest.raises(ValueError, match=r"same shape, not \(7,\) and \(1, 7\)"):
        crane_checker.check_motions(crane.start, crane.goal[None, :])
    with pytest.raises(ValueError, match="row 2"):
        crane_checker.check_motions(states, states)
    with pytest.raises(ValueError, match="raster"):
        rc.Checker(crane, mode="raster").check_motions(crane.start, crane.goal)


def test_plan_errors_are_value_errors(rc, crane, tmp_path):
    with pytest.raises(ValueError, match="no_such_planner"):
        rc.plan(crane, planner="no_such_planner")
    with pytest.raises(ValueError, match="time_limit"):
        rc.plan(crane, time_limit=0)
    with pytest.raises(ValueError, match="seed"):
        rc.plan(crane, seed=-1)
    with pytest.raises(TypeError):
        rc.plan(crane, seed="one")
    with pytest.raises(ValueError, match="range"):
        rc.plan(crane, planner="rrtconnect", params={"range": "far"})
    with pytest.raises(ValueError, match="start"):
        rc.plan(crane, start=crane.start[:3])
    bare = rc.load(SOURCE / "robots/crane/crane.urdf")
    assert bare.start is None and bare.goal is None
    with pytest.raises(ValueError, match="has no start"):
        rc.plan(bare)


# ---- threads --------------------------------------------------------------------------------

def test_python_threads_share_one_checker_and_get_the_single_thread_verdicts(rc, crane):
    checker = rc.Checker(crane, threads=1)
    batches = [random_states(crane, 200, seed=s) for s in range(4)]
    expected = [checker.check(batch) for batch in batches]
    assert any(e.any() for e in expected) and not all(e.all() for e in expected)
    results = [None] * len(batches)

    def work(i):
        results[i] = [checker.check(batches[i]) for _ in range(3)]

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(batches))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for got, want in zip(results, expected):
        for verdicts in got:
            np.testing.assert_array_equal(verdicts, want)


def test_check_releases_the_gil_while_it_works(rc, crane):
    """The main thread keeps running Python while another thread's check() decides a large batch:
    with the GIL held, it would stand still for the whole batch."""
    checker = rc.Checker(crane, threads=1)
    batch = random_states(crane, 20_000, seed=9)
    span = {}

    def work():
        span["start"] = time.perf_counter()
        checker.check(batch)
        span["end"] = time.perf_counter()

    worker = threading.Thread(target=work)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    seconds = span["end"] - span["start"]
    assert seconds > 0.05, "the batch is too small to tell"
    # With the GIL held the main thread could not tick at all during the batch; released, it ticks
    # thousands of times even when the scheduler gives it only part of a loaded machine (a bound
    # on the longest gap flaked there).
    during = [t for t in ticks if span["start"] < t < span["end"]]
    assert len(during) > 100, f"the main thread ticked {len(during)} times during the {seconds:.3f} s batch"
