"""The model from Python: the same numbers as the Rust model (digit for digit on the bench
scenes), solve_many the same as a loop of solve, each refusal as its exception, no NaN."""

import math

import numpy as np
import pytest

import softfinger as sf

# the board's finger hanging under its weight at 0.5 N, every stack at 3,800 V (the board's answer) (issue 53: a uniform
# posture is out of its reach; its stacks change a joint's stiffness by 1 %)
REACHED_DEG = [4.66, 5.35, 6.21]


def bench_finger(layers: int, fidelity: bool, grav_dir=None) -> sf.Finger:
    """finger-scenes' `params`: docs/model.md's default values with the hinge model pinned (and
    standard gravity along `grav_dir` degrees, if given)."""
    m, plate, flex = (8, 1, 1) if fidelity else (1, 0, 0)
    g = {} if grav_dir is None else {"grav": 9.81, "grav_dir": grav_dir}
    return sf.Finger(preset="default", layers=layers, m=m, plate=plate, flex_links=flex, **g)


def parse_reference(line: str):
    head, *parts = [p.strip() for p in line.split("|")]
    name, method, *nums = head.split()
    tension, volts = float(nums[0]), [float(v) for v in nums[1:4]]
    return name, method, tension, volts, parts


SCENE_MODEL = {  # name -> (layers, fidelity), as finger-scenes' SCENES
    "bare-0.2N": (0, False), "bare-0.5N": (0, False), "bare-1.0N": (0, False),
    "de-0.2N": (4, False), "de-0.5N": (4, False), "de-1.0N": (4, False),
    "de-1.0N-uni8kV": (4, False), "de-1.0N-per9/5/0kV": (4, False),
    "bare-7N": (0, False), "bare-250N-contact": (0, False),
    "bare-1.0N-fid": (0, True), "de-1.0N-per9/5/0kV-fid": (4, True),
    "de-1.0N-per9/5/0kV-fid-g0": (4, True, 0.0), "de-1.0N-per9/5/0kV-fid-g90": (4, True, 90.0),
}


def test_results_equal_the_rust_model_digit_for_digit(reference_lines):
    seen = set()
    for line in reference_lines:
        name, method, tension, volts, parts = parse_reference(line)
        f = bench_finger(*SCENE_MODEL[name])
        kw = {"method": "converged"} if method == "converged" else {"method": "stepping", "n_inc": 20}
        seen.add((name, method))
        if parts[0].startswith("err"):
            with pytest.raises(sf.FingerError) as e:
                f.solve(tension, volts, **kw)
            assert parts[0] == f"err {e.value.kind}" or parts[0].startswith(f"err {e.value.kind} "), (line, e.value)
            continue
        s = f.solve(tension, volts, **kw)
        joints, tip, cable, thick, stiff, iters = parts
        # the reference prints each f64 in Rust's shortest round-trip form: parse it back and
        # the bits must be the same
        assert s.joints_rad.tolist() == [float(x) for x in joints.split()], line
        assert s.tip.tolist() == [float(x) for x in tip.split()], line
        assert s.cable_mm == float(cable), line
        assert s.thickness_mm.tolist() == [float(x) for x in thick.split()], line
        k = s.stiffness
        assert [k[0, 0], k[1, 1], k[2, 2]] == [float(x) for x in stiff.split()], line
        assert s.iterations == int(iters), line
    assert len(seen) == 2 * len(SCENE_MODEL), "every bench scene, both methods"


def test_solve_many_equals_a_loop_of_solve():
    f = sf.Finger()
    rng = np.random.default_rng(7)
    n = 64
    P = rng.uniform(0.0, 3.0, n)
    V = rng.uniform(0.0, 0.99 * f.ceiling(), (n, 3))
    many = f.solve_many(P, V)
    assert len(many) == n and many.ok.all() and many.errors == []
    for i in range(n):
        s = f.solve(P[i], V[i])
        assert np.array_equal(many.joints_rad[i], s.joints_rad)
        assert np.array_equal(many.nodes[i], s.nodes)
        assert np.array_equal(many.tip[i], s.tip)
        assert many.cable_mm[i] == s.cable_mm
        assert np.array_equal(many.thickness_mm[i], s.thickness_mm)
        assert np.array_equal(many.stiffness[i], s.stiffness)
        assert many.iterations[i] == s.iterations and many.residual_mm[i] == s.residual_mm
    # broadcasting: one tension for every row, one voltage set for every row
    same = f.solve_many(1.0, np.zeros((4, 3)))
    assert np.array_equal(same.joints_rad, np.repeat(f.solve(1.0, [0, 0, 0]).joints_rad[None], 4, axis=0))
    assert f.solve_many([0.5, 1.0], [0, 1000, 2000]).joints_rad.shape == (2, 3)
    with pytest.raises(ValueError):
        f.solve_many([0.5, 1.0], np.zeros((3, 3)))


def test_shapes_units_and_no_nan():
    f = sf.Finger()
    c = f.ceiling()
    s = f.solve(1.0, [0, 0.3 * c, 0.6 * c])
    assert s.joints_rad.shape == (3,) and s.nodes.shape == (4, 3) and s.tip.shape == (3,)
    assert s.stiffness.shape == (3, 3) and s.thickness_mm.shape == (3,)
    assert np.allclose(np.degrees(s.joints_rad), s.joints_deg)
    assert np.array_equal(s.nodes[-1], s.tip) and np.array_equal(s.nodes[0], [0, 0, 0])
    # a thinner stack (more voltage) bends its joint more: the model's physics, not a constant
    assert s.joints_rad[2] > s.joints_rad[1] > s.joints_rad[0]
    assert s.thickness_mm[0] == pytest.approx(2.0) and s.thickness_mm[2] < s.thickness_mm[0]
    assert "Solution(" in repr(s)
    # a mask of refused rows: NaN in every result (numpy's missing value; was 0, a straight
    # finger in a plot), the asked tension and voltages kept, ok False
    many = f.solve_many([1.0, 1.0, 50.0], [[0, 0, 0], [0, 0, 2 * f.ceiling()], [0, 0, 0]], errors="mask")
    assert many.ok.tolist() == [True, False, False]
    assert [i for i, _ in many.errors] == [1, 2]
    assert isinstance(many.errors[0][1], sf.VoltageCeilingError) and many.errors[0][1].index == 1
    for a in (many.joints_rad, many.nodes, many.tip, many.cable_mm, many.thickness_mm, many.stiffness, many.residual_mm):
        assert np.isfinite(a[0]).all() and np.isnan(a[1:]).all()
    assert many.tension_N.tolist() == [1.0, 1.0, 50.0] and many.volts_V[1, 2] == 2 * f.ceiling()
    assert many.iterations[1:].tolist() == [0, 0]
    # pose: the inverse lands on the forward model
    target = f.solve(1.0, [0.2 * c, 0.5 * c, 0.8 * c]).joints_rad
    p = f.pose(target)
    lo, hi = p.interval_N
    assert lo <= p.tension_N <= hi and not p.tension_given
    back = f.solve(p.tension_N, p.volts_V)
    assert np.allclose(back.joints_rad, target, atol=1e-6)
    given = f.pose(np.degrees(target), P=float(p.interval_N.mean()), degrees=True)
    assert given.tension_given and np.allclose(given.angles_rad, target)
    assert np.allclose(f.solve(given.tension_N, given.volts_V).joints_rad, target, atol=1e-6)
    c = f.contact(1.0, 1.5, [0, 0, 0])
    assert c.magnitude_N > 0 and np.allclose(c.solution.tip[:2], c.point_mm, atol=1e-6)
    b = f.fmax([0, 0, 0])
    assert b.kind in ("contact", "limit-point", "search-bound") and 1 <= b.joint <= 3 and b.tension_N > 1.0


def test_each_exception_is_raised_where_the_model_refuses():
    f = sf.Finger()
    ceiling = f.ceiling()
    assert 0 < ceiling <= f.params["v_supply"] and ceiling < f.pull_in_voltage()

    with pytest.raises(sf.VoltageCeilingError) as e:
        f.solve(1.0, [0, 0, ceiling])
    assert (e.value.joint, e.value.volts, e.value.ceiling) == (3, ceiling, ceiling)
    assert e.value.code == "limit" and e.value.kind == "VoltageCeiling"

    # the paper's "2 mm to 1 mm": past the 33 % pull-in limit
    with pytest.raises(sf.ThicknessLimitError) as e:
        f.volts_for_thickness([1.0, 2.0, 2.0])
    assert e.value.joint == 1 and e.value.requested_mm == 1.0
    assert e.value.limit_mm == pytest.approx(2.0 * 2 / 3)

    # one joint bent far more than the others: no voltage within the ceiling holds it
    with pytest.raises(sf.UnreachableError) as e:
        f.pose([0.5, 0.01, 0.01])
    assert e.value.joint == 1 and e.value.needed > e.value.max >= e.value.min > 0
    assert e.value.code == "unreachable"

    with pytest.raises(sf.NotConvergedError) as e:
        f.solve(5.0, [0, 0, 0], max_iter=1)  # below fmax (past it the refusal quotes fmax)
    assert e.value.iterations == 1 and e.value.code == "fault"

    with pytest.raises(sf.InputError) as e:
        f.solve(-1.0, [0, 0, 0])
    assert isinstance(e.value, ValueError) and e.value.input == "tension"
    with pytest.raises(sf.InputError) as e:
        f.solve(math.nan, [0, 0, 0])
    assert e.value.kind == "NonFinite"
    with pytest.raises(sf.InputError) as e:
        sf.Finger(a=100.0)
    assert e.value.kind == "Param" and e.value.name == "a"
    with pytest.raises(TypeError):
        sf.Finger(frobnicate=1.0)

    fmax = f.fmax([0, 0, 0]).tension_N
    with pytest.raises(sf.BranchEndError) as e:
        f.contact(1.0, 2 * fmax, [0, 0, 0])
    assert e.value.kind == "ForceLimit" and e.value.fmax == fmax

    # a tension below P0: the stop would pull on the tip (issue 55)
    with pytest.raises(sf.FingerError) as e:
        f.contact(1.0, 0.5, [0, 0, 0])
    assert e.value.kind == "PullingStop" and e.value.code == "limit" and e.value.force > 0

    # every subclass is a FingerError
    for cls in (sf.VoltageCeilingError, sf.ThicknessLimitError, sf.UnreachableError, sf.NotConvergedError, sf.InputError, sf.BranchEndError):
        assert issubclass(cls, sf.FingerError)

    # solve_many raises the first refused row's exception, with its index
    with pytest.raises(sf.VoltageCeilingError) as e:
        f.solve_many([1.0, 1.0, 1.0], [[0, 0, 0], [0, 0, 2 * ceiling], [0, 0, 3 * ceiling]])
    assert e.value.index == 1


def test_presets_parameters_and_calibration():
    paper = sf.Finger(preset="paper")
    assert paper.params["e_de"] == pytest.approx(0.6 / (2 * 1.49))
    assert paper.params["m"] == 1 and sf.Finger().params["m"] == 8
    assert paper.calibration == [1, 1, 1, 1, 1, 0, 1, 0] and paper.preset == "paper"
    # overrides are taken all at once, in any order (a = 15 fits only with l = 40)
    assert sf.Finger(preset="default", a=15.0, l=40.0).params["a"] == 15.0
    none = [1, 1, 1, 1, 1, 0, 1, 0]
    # the board's finger: VHB 4905 with the board's FE calibration; docs/model.md's finger
    # ("default") is uncalibrated unless asked
    board = sf.Finger()
    assert board.preset == "board" and board.card == "VHB-4905" and board.calibration != none
    assert board.calibration == sf.Finger(preset="default", calibration="model_md").calibration
    assert sf.Finger(preset="default").calibration == none == sf.Finger(calibration=None).calibration
    assert 'calibration="model_md"' in repr(board) and 'calibration="none"' in repr(sf.Finger(calibration=None))
    # a calibration that does not apply is an error, never dropped: another stack count, another
    # film, another hinge model
    for kw in ({"layers": 2}, {"card": "Elastosil-2030"}, {"preset": "default", "m": 1, "calibration": "model_md"}):
        with pytest.raises(sf.InputError) as e:
            sf.Finger(**kw)
        assert "calibration" in str(e.value) and "calibration=None" in str(e.value), kw
    assert sf.Finger(layers=2, calibration=None).params["layers"] == 2
    # the error names the parameter that left the calibrated finger, not those that did not
    # (the board's `param e_b 15` drops the factors by the same rule and says `cal=`)
    for kw, name in (({"e_b": 15}, "e_b"), ({"layers": 2}, "layers"), ({"card": "Elastosil-2030"}, "card")):
        with pytest.raises(sf.InputError) as e:
            sf.Finger(**kw)
        assert e.value.name == name and f"{name} = " in str(e.value), (kw, str(e.value))
        if name == "e_b":
            assert "layers = " not in str(e.value) and "card " not in str(e.value), str(e.value)
    # the calibration changes the answer
    assert not np.array_equal(board.solve(1.0, 0).joints_rad, sf.Finger(calibration=None).solve(1.0, 0).joints_rad)
    names = [n for n, _ in sf.parameter_ranges()]
    assert "margin" in names and set(names) == set(sf.Finger().params)


def test_material_cards():
    names = sf.cards()
    assert "VHB-4905" in names and len(names) >= 3
    default = sf.Finger(preset="default")
    vhb = sf.Finger(preset="default", card="VHB-4905")
    assert vhb.card == "VHB-4905" and sf.Finger(card="vhb").card == "VHB-4905"
    # the board's finger holds the board's hold ceiling (docs/materials.md) with the model's
    assert 0 < sf.Finger().ceiling() <= vhb.ceiling() and "hold ceiling" in repr(sf.Finger())
    # the card's film: its equilibrium modulus by the isotropic rule, a lower ceiling than the
    # default film's, and (softer) more bending at the same fraction of its ceiling
    assert vhb.params["e_de"] == pytest.approx(2 * vhb.params["g"] * (1 + vhb.params["nu"]))
    assert 0 < vhb.ceiling() < default.ceiling() and vhb.ceiling() < vhb.pull_in_voltage()
    frac = [0.0, 0.5, 0.9]
    a = vhb.solve(1.0, [x * vhb.ceiling() for x in frac])
    b = default.solve(1.0, [x * default.ceiling() for x in frac])
    assert a.joints_rad[2] - a.joints_rad[0] > b.joints_rad[2] - b.joints_rad[0] > 0
    with pytest.raises(sf.VoltageCeilingError) as e:
        vhb.solve(1.0, [0, 0, vhb.ceiling()])
    assert e.value.ceiling == vhb.ceiling()
    # a card on another preset keeps that preset's structure
    assert sf.Finger(preset="paper", card="VHB-4905").params["m"] == 1
    with pytest.raises(ValueError):
        sf.Finger(card="unobtainium")


def test_errors_name_the_argument_and_the_limit():
    """What a refusal says: the argument and what it takes, the interval a given tension
    missed, the one figure of the branch's end (`fmax`, the board's `limits`)."""
    f = sf.Finger()
    with pytest.raises(TypeError) as e:
        f.solve(1, "1000")
    assert "volts" in str(e.value) and "3 numbers" in str(e.value) and "str" in str(e.value), str(e.value)
    with pytest.raises(TypeError) as e:
        f.pose("5 5 5")
    assert str(e.value).startswith("angles:"), str(e.value)
    # a posture the board's finger reaches hanging under its weight (issue 53)
    q = f.pose(REACHED_DEG, degrees=True)
    lo, hi = q.interval_N
    for P in (hi + 0.3, lo - 0.3):
        with pytest.raises(sf.UnreachableError) as e:
            f.pose(REACHED_DEG, P=P, degrees=True)
        assert "outside" in str(e.value) and f"{lo:.4f} to {hi:.4f} N" in str(e.value), str(e.value)
    # past the branch's end: fmax itself, as Finger.fmax gives it
    b = f.fmax([0, 0, 0])
    with pytest.raises(sf.BranchEndError) as e:
        f.solve(100.0, 0)
    assert e.value.fmax == b.tension_N and f"fmax={b.tension_N:.4f} N" in str(e.value), str(e.value)
    with pytest.raises(sf.BranchEndError) as e:
        f.contact(1.0, 100.0, [0, 0, 0])
    assert e.value.fmax == b.tension_N, str(e.value)


def test_the_inverse_posture_has_its_stiffness():
    f = sf.Finger()
    q = f.pose(REACHED_DEG, degrees=True)
    k = q.solution.stiffness
    assert k is not None and k.shape == (3, 3)
    assert np.allclose(k, f.solve(q.tension_N, q.volts_V).stiffness, rtol=1e-6)
