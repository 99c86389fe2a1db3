"""Reward features and observation terms on hand-built task states."""

import math

import pytest

from fastrl.terms import OBSERVATION_TERMS, REWARD_FEATURES, InstrumentState, cue_potential, tolerance
from fastrl.terms.vec import mat_quat


def state(**kw) -> InstrumentState:
    """A task state (the scope's and the instruments', which every term may read) with a few fields set."""
    s = InstrumentState()
    for k, v in kw.items():
        setattr(s, k, v)
    return s


def f(name, s, **params):
    """Evaluate a registered reward feature."""
    return REWARD_FEATURES[name].fn(s, **params)


def test_tolerance_kernel_is_one_inside_and_a_tenth_at_one_margin():
    assert tolerance(0.03, 0.02, 0.05, 0.01) == 1.0
    assert tolerance(0.06, 0.02, 0.05, 0.01) == pytest.approx(0.1)
    assert tolerance(0.01, 0.02, 0.05, 0.01) == pytest.approx(0.1)
    assert tolerance(0.055, 0.02, 0.05, 0.01) > tolerance(0.06, 0.02, 0.05, 0.01) > tolerance(0.08, 0.02, 0.05, 0.01)


def test_angle_distance_horizon_features_follow_the_cue():
    s = state(centring=math.radians(5), tol_centring=math.radians(8), distance=0.03, horizon=0.5, tol_horizon=0.26)
    assert f("angle", s) == 1.0
    assert f("distance", s) == 1.0
    assert 0.0 < f("horizon", s) < 1.0
    s.centring = math.radians(8 + 20)
    assert f("angle", s, margin_deg=20) == pytest.approx(0.1)


def test_progress_completed_contact_time():
    s = state(dwell_gain=0.2, completed=True, contacts=2)
    assert f("progress", s) == pytest.approx(0.2)
    assert f("completed", s) == 1.0 and f("contact", s) == 1.0 and f("time", s) == 1.0
    s = state(dwell_gain=0.0, completed=False, contacts=0)
    assert f("progress", s) == 0.0 and f("completed", s) == 0.0 and f("contact", s) == 0.0


def test_velocity_penalty_counts_only_speed_above_the_limit():
    assert f("velocity", state(tip_speed=0.04), max_speed=0.05) == 0.0
    assert f("velocity", state(tip_speed=0.1), max_speed=0.05) == pytest.approx(1.0)


def test_shaping_is_gamma_phi_next_minus_phi():
    s = state(centring=0.1, tol_centring=0.2, horizon=0.0, distance=0.03, gamma=0.9)
    s.potential = cue_potential(s)
    s.prev_potential = -2.0
    assert s.potential == pytest.approx(-0.5)
    assert f("shaping", s) == pytest.approx(0.9 * -0.5 + 2.0)


def test_potential_counts_distance_outside_the_range():
    s = state(centring=0.0, horizon=0.0, distance=0.08, dist_lo=0.02, dist_hi=0.05)
    assert cue_potential(s) == pytest.approx(-(0.03 / 0.03))
    assert s.distance_error == pytest.approx(0.03)


def test_visible_uses_half_the_field_of_view():
    assert f("visible", state(centring=0.3, fov=1.0)) == 1.0
    assert f("visible", state(centring=0.6, fov=1.0)) == 0.0


def test_line_steadiness_shaft_and_rays_read_their_fields():
    assert f("line_deviation", state(line_deviation=0.01), scale=0.005) == pytest.approx(2.0)
    assert f("steadiness", state(tip_accel=(3.0, 4.0, 0.0))) == pytest.approx(5.0)
    assert f("shaft_motion", state(portal_vel=(0.3, 0.4, 1.0, 1.0, 1.0))) == pytest.approx(0.5)
    assert f("rays", state(ray_fraction=0.75)) == 0.75


def test_observation_terms_have_their_declared_sizes():
    s = state(goals=(0.1, 0.2, 0.3))
    for name, term in OBSERVATION_TERMS.items():
        assert len(term.fn(s)) == term.width([]), name
    two = state(  # a probe (4 coordinates) and a grasper (5)
        instruments_pos=(0.0,) * 6,
        instruments_quat=(1.0, 0.0, 0.0, 0.0) * 2,
        instruments_vel=(0.0,) * 6,
        instruments_to_target=(0.0,) * 6,
        instruments_touching=(True, False),
        instruments_in_view=(False, True),
        instruments_portal=(0.0,) * 9,
    )
    for name, term in OBSERVATION_TERMS.items():
        assert len(term.fn(two)) == term.width([4, 5]), name
    assert OBSERVATION_TERMS["tool_tip_pos"].width([4, 5]) == 6 and OBSERVATION_TERMS["tool_portal"].width([4, 5]) == 9


def test_target_in_camera_and_horizon_error():
    s = state(
        cam_pos=(0.0, 0.0, 0.0),
        cam_fwd=(0.0, 0.0, -1.0),
        cam_up=(0.0, 1.0, 0.0),
        cam_right=(1.0, 0.0, 0.0),
        target_pos=(0.0, 0.0, -0.05),
        target_up=(1.0, 0.0, 0.0),
    )
    assert OBSERVATION_TERMS["target_in_camera"].fn(s) == pytest.approx((0.0, 0.0, 1.0))
    assert OBSERVATION_TERMS["horizon_error"].fn(s) == pytest.approx((1.0, 0.0))


def test_mat_quat_matches_a_known_rotation():
    c, s_ = math.cos(0.3), math.sin(0.3)
    q = mat_quat((c, -s_, 0.0, s_, c, 0.0, 0.0, 0.0, 1.0))
    assert q == pytest.approx((math.cos(0.15), 0.0, 0.0, math.sin(0.15)))


def test_feature_params_are_checked_against_the_signature():
    assert REWARD_FEATURES["velocity"].check_params({"max_speed": 0.1}) == []
    assert REWARD_FEATURES["velocity"].check_params({"max_sped": 0.1})[0][0] == "max_sped"
    assert REWARD_FEATURES["velocity"].check_params({"max_speed": "fast"})[0][1].startswith("must be a number")


def test_every_term_parameter_has_a_domain_its_default_lies_in():
    """Each registered term declares a domain per parameter; registering one without it fails at import."""
    from fastrl.terms.registry import Registry

    for term in [*REWARD_FEATURES.values(), *OBSERVATION_TERMS.values()]:
        assert set(term.domains) == set(term.params), term.name
        assert term.check_params({k: p.default for k, p in term.params.items()}) == [], term.name
    with pytest.raises(TypeError, match="domains"):
        Registry("test").register(lambda s, margin=0.1: s)


@pytest.mark.parametrize(
    ("name", "params"),
    [
        ("distance", {"margin": 0}),
        ("distance", {"margin": -0.02}),
        ("velocity", {"max_speed": 0.0}),
        ("angle", {"margin_deg": 5e-324}),
        ("horizon", {"margin_deg": float("inf")}),
        ("line_deviation", {"scale": float("nan")}),
        ("steadiness", {"scale": -1}),
        ("tool_near", {"within": -0.001}),
        ("tool_near", {"margin": 1e-300}),
    ],
)
def test_parameters_that_divide_by_zero_or_overflow_are_refused(name, params):
    """The values issue 42 found (margin 0, negative margins) and their kin: each named, with the domain in words."""
    [(key, problem)] = REWARD_FEATURES[name].check_params(params)
    assert key in params and problem.startswith("must be a") and repr(params[key]) in problem, problem
    assert REWARD_FEATURES[name].domains[key].problem(REWARD_FEATURES[name].params[key].default) is None


def test_tolerance_is_zero_far_outside_without_overflow():
    """At the smallest margin a domain allows, far outside the band: 0, not an OverflowError."""
    assert tolerance(1.0, 0.0, 0.01, math.radians(1e-6)) == 0.0
    assert 0.0 < tolerance(0.0105, 0.0, 0.01, 0.001) < 1.0


def test_progress_cannot_be_farmed_by_leaving_and_refilling_the_dwell_bar():
    from fastrl.env.cues import update_dwell

    s = state(centring=0.0, horizon=0.0, distance=0.03, dwell_time=1.0)
    elapsed, total = 0.0, 0.0
    for green in [True] * 8 + [False] + [True] * 8 + [False] + [True] * 12:
        s.centring = 0.0 if green else 1.0
        elapsed = update_dwell(s, elapsed, 0.1)
        total += f("progress", s)
    assert s.completed and total == pytest.approx(1.0)
