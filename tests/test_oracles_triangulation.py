"""Triangulation's options against poses worked out by hand.

A view seen from a known pose ``T`` is the local map's surfaces moved by ``T⁻¹`` (by hand:
``R(−θ)(p − t)``). An affordance from a pair of matching endpoints is ``p_local −
R(θ) p_view``: exactly ``T`` for a true pair, and ``T + δ`` when the local map holds that
end displaced by ``δ`` (an occluded end cut short, or an observation shifted along its
own line). So each option's choice of endpoint and of affordance has a known answer:

- every option combination (the array path, reached by non-default options or by nine
  surfaces) recovers ``T`` from an exact view;
- ``position_endpoint``: ``"both"`` and ``"local_key"`` ignore a local end that is
  occluded (and displaced); ``"current_real"`` uses it when it is the nearer: ``T + δ``;
- ``choose``: ``"nearest_to_pi"`` takes the affordance nearest path integration,
  ``"fitness"`` the long wall's (its fitness worked out below).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from albot2d.geometry import Pose
from albot2d.mapping.albot1.triangulation import TriangulationParams, pose_affordances, triangulate
from albot2d.perception.surfaces import Surfaces

T = Pose(0.7, -0.4, math.radians(25.0))
ROOM = np.array(
    [
        [3.0, -2.0, 3.0, 2.0],
        [2.5, 2.5, -1.0, 2.5],
        [-1.5, 2.0, -1.5, -1.0],
        [-1.0, -2.5, 2.0, -2.5],
        [4.0, -1.0, 5.0, 0.5],
        [1.0, 3.5, 0.0, 4.5],
        [-2.5, -0.5, -3.0, -2.0],
        [0.5, -3.5, 1.5, -4.0],
        [2.0, 1.0, 2.0, 1.6],
    ]
)


def in_view(segs: np.ndarray, pose: Pose) -> np.ndarray:
    """Segments of the local map as seen from ``pose``: ``R(−θ)(p − t)`` by hand."""
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    pts = segs.reshape(-1, 2) - [pose.x, pose.y]
    local = np.column_stack([c * pts[:, 0] + s * pts[:, 1], -s * pts[:, 0] + c * pts[:, 1]])
    return local.reshape(-1, 4)


def assert_pose(got: Pose | None, want: Pose, atol: float = 1e-9) -> None:
    assert got is not None
    assert (got.x, got.y) == pytest.approx((want.x, want.y), abs=atol)
    assert math.remainder(got.theta - want.theta, 2 * math.pi) == pytest.approx(0.0, abs=atol)


PI = Pose(T.x + 0.05, T.y - 0.03, T.theta + math.radians(1.0))

OPTIONS = [
    {},
    {"choose": "fitness"},
    {"heading": "inlier_mean"},
    {"heading": "selected"},
    {"position_endpoint": "current_real"},
    {"position_endpoint": "local_key"},
    {"prefer_nearer_endpoint": False},
    {"use_outlier_heuristic": False},
    {"choose": "fitness", "heading": "inlier_mean", "use_outlier_heuristic": False},
]


@pytest.mark.parametrize("options", OPTIONS, ids=lambda o: "-".join(map(str, o.values())))
@pytest.mark.parametrize("count", [4, 9])
def test_every_option_recovers_the_true_pose_from_an_exact_view(options: dict, count: int) -> None:
    params = TriangulationParams(**options)
    local = Surfaces.from_segments(ROOM[:count])
    current = Surfaces.from_segments(in_view(ROOM[:count], T))
    assert_pose(triangulate(local, current, PI, params), T)


def _cut_wall(robot: Pose) -> tuple[Surfaces, Surfaces]:
    """One wall x = 3, y ∈ [−2, 2]: seen whole in the view, but in the local map its
    second end was occluded and stops 0.5 m short, at (3, 1.5)."""
    local = Surfaces.from_segments([[3.0, -2.0, 3.0, 1.5]], [[False, True]])
    current = Surfaces.from_segments(in_view(np.array([[3.0, -2.0, 3.0, 2.0]]), robot))
    return local, current


@pytest.mark.parametrize(
    ("endpoint", "prefer_nearer", "shift_y"),
    [
        ("both", True, 0.0),  # the local end is occluded: only end 0 is usable
        ("local_key", True, 0.0),  # the local key end is its real one, end 0
        ("current_real", True, -0.5),  # end 1 is real in the view and the nearer
        ("current_real", False, 0.0),  # end 0 first when nearness is not preferred
    ],
)
def test_which_endpoint_affords_the_position(
    endpoint: str, prefer_nearer: bool, shift_y: float
) -> None:
    """From (0.7, 0.6) the wall's end (3, 2) is 2.69 m away and (3, −2) 3.47 m. Using the
    local map's cut end (3, 1.5) with the view's (3, 2) places the robot 0.5 m short:
    (0.7, 0.1); the direction (and so the heading) is the same either way."""
    robot = Pose(0.7, 0.6, math.radians(25.0))
    local, current = _cut_wall(robot)
    params = TriangulationParams(
        position_endpoint=endpoint,  # type: ignore[arg-type]
        prefer_nearer_endpoint=prefer_nearer,
    )
    want = Pose(robot.x, robot.y + shift_y, robot.theta)
    assert_pose(triangulate(local, current, robot, params, gate=(1.0, 5.0)), want)
    aff = pose_affordances(local, current, robot.theta, params)
    assert len(aff.poses) == 1
    np.testing.assert_allclose(aff.poses[0], [want.x, want.y, want.theta], atol=1e-9)


def test_pose_affordances_pairs_swapped_ends_when_a_surface_is_seen_reversed() -> None:
    """The view lists the wall's ends the other way round (as after turning round): the
    direction differs by π, resolved by the heading hint, and end 0 of the local map
    pairs with end 1 of the view: still the true pose, for each surface."""
    segs = ROOM[:4]
    view = in_view(segs, T)[:, [2, 3, 0, 1]]
    aff = pose_affordances(Surfaces.from_segments(segs), Surfaces.from_segments(view), T.theta)
    assert aff.surface.tolist() == [0, 1, 2, 3]
    np.testing.assert_allclose(aff.poses, np.tile([T.x, T.y, T.theta], (4, 1)), atol=1e-9)


def test_fitness_prefers_the_long_wall_where_path_integration_prefers_the_short() -> None:
    """Two surfaces: a 4 m wall (x = 3) seen exactly, affording T; a 0.5 m ledge
    (y = 2.5) whose local observation is shifted 0.3 m along itself, affording
    T + (0.3, 0). Path integration at T + (0.25, 0): the ledge's affordance is 0.05 m
    from it, the wall's 0.25 m, so ``nearest_to_pi`` takes the ledge. Fitness
    length·(400 − d)·(5 − Δθ)/max(range, 2000) in mm and degrees, d the distance of the
    view's end moved by path integration from the local end (0.25 m for the wall, 0.05 m
    for the ledge): the wall's 4000·150·5/r > the ledge's 500·350·5/r' for any ranges
    of 2–3.5 m, so ``fitness`` takes the wall: T exactly."""
    local = np.array([[3.0, -2.0, 3.0, 2.0], [1.3, 2.5, 0.8, 2.5]])
    truth = np.array([[3.0, -2.0, 3.0, 2.0], [1.0, 2.5, 0.5, 2.5]])
    current = Surfaces.from_segments(in_view(truth, T))
    pi = Pose(T.x + 0.25, T.y, T.theta)
    local_s = Surfaces.from_segments(local)
    nearest = triangulate(local_s, current, pi, TriangulationParams(choose="nearest_to_pi"))
    assert_pose(nearest, Pose(T.x + 0.3, T.y, T.theta))
    fitness = triangulate(local_s, current, pi, TriangulationParams(choose="fitness"))
    assert_pose(fitness, T)


def test_local_key_end_is_paired_through_swapped_ends() -> None:
    """The cut wall seen reversed (ends listed the other way round): the local map's key
    end is its real end 0, which pairs with the view's end 1; the affordance is the true
    pose, not the one the cut end (0.5 m short) would give."""
    robot = Pose(0.7, 0.6, math.radians(25.0))
    local, current = _cut_wall(robot)
    swapped = Surfaces.from_segments(current.segments[:, [2, 3, 0, 1]])
    params = TriangulationParams(position_endpoint="local_key")
    aff = pose_affordances(local, swapped, robot.theta, params)
    np.testing.assert_allclose(aff.poses, [[robot.x, robot.y, robot.theta]], atol=1e-9)


def _two_walls_one_turned() -> tuple[Surfaces, Surfaces, float]:
    """Walls A (x = 3) and B (y = 2.5) seen from T; B's observation turned by +0.6°
    about its end 0 in the view, so B affords heading T.θ − 0.6° (and a position a few
    cm off). Returns (local, current, 0.6° in radians)."""
    eps = math.radians(0.6)
    local = np.array([[3.0, -2.0, 3.0, 2.0], [2.5, 2.5, -1.0, 2.5]])
    view = in_view(local, T)
    b0, b1 = view[1, :2], view[1, 2:]
    c, s = math.cos(eps), math.sin(eps)
    d = b1 - b0
    view[1, 2:] = b0 + np.array([c * d[0] - s * d[1], s * d[0] + c * d[1]])
    return Surfaces.from_segments(local), Surfaces.from_segments(view), eps


def test_heading_options_on_two_affordances_that_disagree_by_0_6_degrees() -> None:
    """Path integration at T: A (exact, 0 m off) is chosen. ``"selected"`` keeps its
    pose, T. ``"inlier_mean"`` moves the heading by the mean deviation of the kept
    affordances within 1°, (0 − 0.6°)/2, and places the robot by A's endpoint pair at that
    heading: p_local − R(h)·p_view, with A's nearer end in the view."""
    local, current, eps = _two_walls_one_turned()
    selected = triangulate(local, current, T, TriangulationParams(heading="selected"))
    assert_pose(selected, T)
    h = T.theta - eps / 2
    view_a = current.segments[0].reshape(2, 2)
    k = int(np.argmin(np.hypot(view_a[:, 0], view_a[:, 1])))
    pc, pl = view_a[k], local.segments[0].reshape(2, 2)[k]
    want = pl - [
        math.cos(h) * pc[0] - math.sin(h) * pc[1],
        math.sin(h) * pc[0] + math.cos(h) * pc[1],
    ]
    got = triangulate(local, current, T, TriangulationParams(heading="inlier_mean"))
    assert_pose(got, Pose(float(want[0]), float(want[1]), h))


def test_weighted_heading_weighs_directions_by_beams_and_length() -> None:
    """The directions' inverse-variance weights n·L² per observation (n beams, L metres),
    combined as 1/(1/w_local + 1/w_view). A (4 m) from 100 beams in both views, B (3.5 m)
    from 10: weights 100·16/2 = 800 and 10·12.25/2 = 61.25; B's direction is 0.6° off,
    so the heading is T.θ − 0.6°·61.25/861.25, both within the 1° consensus."""
    from albot2d.mapping.albot1.triangulation import heading_from_directions

    local, current, eps = _two_walls_one_turned()
    beams = np.array([[0, 99], [200, 209]])
    local = Surfaces(local.segments, local.occluded, beams)
    current = Surfaces(current.segments, current.occluded, beams)
    got = heading_from_directions(local, current, T)
    assert got == pytest.approx(T.theta - eps * 61.25 / 861.25, abs=1e-12)


def test_pi_fitness_by_hand() -> None:
    """One affordance: its view end (1, 2) moved by path integration (0.5, 0.2, 0) lands
    at (1.5, 2.2), 0.1 m from its local end (1.6, 2.2); heading 1° from path
    integration; the surface 2 m long, its end 2.236 m away:
    2000·(400 − 100)·(5 − 1)/2236.07."""
    from albot2d.mapping.albot1.triangulation import Affordances, _pi_fitness

    aff = Affordances(
        np.array([[0.0, 0.0, math.radians(1.0)]]),
        np.array([0]),
        np.array([[1.6, 2.2]]),
        np.array([[1.0, 2.0]]),
    )
    current = Surfaces.from_segments([[1.0, 2.0, 1.0, 4.0]])
    got = _pi_fitness(aff, current, Pose(0.5, 0.2, 0.0))
    assert got[0] == pytest.approx(2000 * 300 * 4 / (1000 * math.hypot(1.0, 2.0)), rel=1e-9)


def test_no_affordance_is_four_empty_arrays() -> None:
    """A wall with both ends occluded in the local map affords no position."""
    local = Surfaces.from_segments([[3.0, -2.0, 3.0, 2.0]], [[True, True]])
    current = Surfaces.from_segments(in_view(local.segments, T))
    aff = pose_affordances(local, current, T.theta)
    assert [a.shape for a in aff] == [(0, 3), (0,), (0, 2), (0, 2)]
    assert triangulate(local, current, T, TriangulationParams(heading="selected")) is None


def test_params_and_inputs_are_checked_by_name() -> None:
    from albot2d.errors import InputError
    from albot2d.mapping.albot1.triangulation import heading_from_directions

    with pytest.raises(InputError, match=r"heading_consensus_deg must be >= 0, got -1\.0"):
        TriangulationParams(heading_consensus_deg=-1.0)
    with pytest.raises(
        InputError,
        match=r"^TriangulationParams.position_endpoint must be both, local_key or "
        r"current_real, got 'any'$",
    ):
        TriangulationParams(position_endpoint="any")  # type: ignore[arg-type]
    two = Surfaces.from_segments(ROOM[:2])
    with pytest.raises(ValueError, match=r"^local has 2 surfaces but current has 1$"):
        heading_from_directions(two, two.select([0]), T)


def test_pi_fitness_by_hand_with_a_turned_path_integration() -> None:
    """Path integration (0.5, 0.2, 90°) moves the view end (1, 2) to (−1.5, 1.2); the
    local end (−1.5, 1.5) is 0.3 m from it; the affordance heading 92°: 2° off. The
    surface 2 m long, its end 2.236 m away: 2000·(400 − 300)·(5 − 2)/2236.07."""
    from albot2d.mapping.albot1.triangulation import Affordances, _pi_fitness

    aff = Affordances(
        np.array([[0.0, 0.0, math.radians(92.0)]]),
        np.array([0]),
        np.array([[-1.5, 1.5]]),
        np.array([[1.0, 2.0]]),
    )
    current = Surfaces.from_segments([[1.0, 2.0, 1.0, 4.0]])
    got = _pi_fitness(aff, current, Pose(0.5, 0.2, math.pi / 2))
    assert got[0] == pytest.approx(2000 * 100 * 3 / (1000 * math.hypot(1.0, 2.0)), rel=1e-9)


def test_fitness_chooses_the_long_wall_listed_second() -> None:
    """The fitness test above with the two surfaces in the other order."""
    local = np.array([[1.3, 2.5, 0.8, 2.5], [3.0, -2.0, 3.0, 2.0]])
    truth = np.array([[1.0, 2.5, 0.5, 2.5], [3.0, -2.0, 3.0, 2.0]])
    current = Surfaces.from_segments(in_view(truth, T))
    pi = Pose(T.x + 0.25, T.y, T.theta)
    got = triangulate(
        Surfaces.from_segments(local), current, pi, TriangulationParams(choose="fitness")
    )
    assert_pose(got, T)
