"""Gravity's parameters from Python (issue 53): `Finger(grav=..., grav_dir=..., rho_b=...)`
with range errors naming the parameter; the board's finger hangs straight down under standard
gravity as the board's does, the other presets have none; `solve_many` takes the orientation
per call or per row; the board's `status` and `limits` carry the orientation in force."""

import math

import numpy as np
import pytest

import softfinger as sf


def test_the_boards_finger_hangs_straight_down_and_the_other_presets_have_no_gravity():
    board = sf.Finger()
    assert (board.params["grav"], board.params["grav_dir"], board.params["rho_b"]) == (9.81, 0.0, 1.19)
    for preset in ("paper", "paper_model", "default"):
        assert sf.Finger(preset=preset).params["grav"] == 0.0, preset
    # gravity keeps the board's FE calibration (computed without it)
    for kw in ({"grav_dir": 90.0}, {"grav": 0.0}, {"grav": 20.0, "grav_dir": -180.0, "rho_b": 1.3}):
        f = sf.Finger(**kw)
        assert f.calibration == board.calibration, kw
        assert all(f.params[k] == v for k, v in kw.items()), kw


def test_gravity_out_of_range_or_not_a_number_names_the_parameter():
    ranges = dict(sf.parameter_ranges())
    assert ranges["grav"].startswith("0..20") and ranges["grav_dir"].startswith("-180..180") and ranges["rho_b"].startswith("0..25")
    for name, bad in [("grav", -0.5), ("grav", 20.5), ("grav_dir", 180.5), ("grav_dir", -181.0), ("rho_b", -1.0),
                      ("rho_b", 26.0), ("grav", math.nan), ("grav_dir", math.nan), ("grav_dir", math.inf)]:
        with pytest.raises(sf.InputError) as e:
            sf.Finger(**{name: bad})
        # out of range: kind Param, its `name`; not a number: kind NonFinite, its `input`
        assert e.value.fields.get("name", e.value.fields.get("input")) == name and name in str(e.value), (name, bad, e.value)


def test_solve_many_takes_the_orientation_per_call_or_per_row():
    f = sf.Finger()
    V = [0.0, 1000.0, 2000.0]
    dirs = np.array([0.0, 90.0, -90.0, 180.0, 90.0])
    P = np.linspace(0.2, 1.5, len(dirs))
    # per row: each row equals the finger of that orientation
    many = f.solve_many(P, V, grav_dir=dirs)
    assert len(many) == len(dirs) and many.ok.all()
    for i, d in enumerate(dirs):
        s = sf.Finger(grav_dir=d).solve(P[i], V)
        assert np.array_equal(many.joints_rad[i], s.joints_rad), d
        assert np.array_equal(many.tip[i], s.tip) and np.array_equal(many.stiffness[i], s.stiffness), d
    # one orientation for every row
    one = f.solve_many(P, V, grav_dir=90)
    h = sf.Finger(grav_dir=90)
    for i in range(len(P)):
        assert np.array_equal(one.joints_rad[i], h.solve(P[i], V).joints_rad)
    # None: the finger's own; scalar P and volts with an array of orientations broadcast
    assert np.array_equal(f.solve_many(P, V, grav_dir=None).joints_rad, f.solve_many(P, V).joints_rad)
    b = f.solve_many(1.0, V, grav_dir=[0.0, 90.0])
    assert b.joints_rad.shape == (2, 3)
    assert np.array_equal(b.joints_rad[1], h.solve(1.0, V).joints_rad)
    # the finger itself is unchanged
    assert f.params["grav_dir"] == 0.0
    with pytest.raises(ValueError):
        f.solve_many(P, V, grav_dir=[0.0, 90.0])
    for bad in (200.0, [0.0, math.nan, 0.0, 0.0, 0.0]):
        with pytest.raises(sf.InputError) as e:
            f.solve_many(P, V, grav_dir=bad)
        assert e.value.fields.get("name", e.value.fields.get("input")) == "grav_dir", bad


def test_the_board_shows_the_orientation_the_python_board_finger_has(sim_program):
    f = sf.Finger()
    with sf.Board.sim(sim_program) as b:
        for reply in (b.status(), b.limits()):
            assert (reply.grav_m_s2, reply.grav_dir_deg) == (f.params["grav"], f.params["grav_dir"]), reply
        assert b.param("rho_b")["rho_b"] == f.params["rho_b"]
        b.param("grav_dir", 90)
        assert b.status().grav_dir_deg == 90.0 and b.limits().grav_dir_deg == 90.0
        with pytest.raises(sf.BoardError) as e:
            b.param("grav_dir", 181)
        assert e.value.code == "usage" and "grav_dir" in e.value.message
        b.preset("paper")
        assert b.status().grav_m_s2 == 0.0 == sf.Finger(preset="paper").params["grav"]
