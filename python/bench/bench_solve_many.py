"""Throughput of `Finger.solve_many` against a plain NumPy/SciPy implementation of the same
three-element equilibrium (written here, for this benchmark: scipy.optimize per posture) and
against a Python loop over `Finger.solve`.

The finger is the paper's model (`preset="paper_model"`: the default values, one compliance per
hinge, the body modulus, rigid links), the one a SciPy script would write from the paper and
docs/model.md; the SciPy version's joint angles are checked against the Rust model's first. No tip
stiffness on either side (`stiffness=False`). Two scenes: without gravity, and with it
(9.81 m/s², held horizontally: the SciPy version carries the weight as the model does, lumped
per element, docs/model.md "Gravity"). Postures: tensions uniform in [0, 2] N, voltages
uniform in [0, 0.9 x ceiling]
(the ceiling is the model's: `Finger.ceiling()`).

Run: `target/pyenv/bin/python python/bench/bench_solve_many.py` (from the top); with
`--write-docs` it rewrites the generated table of docs/python.md.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import time
from pathlib import Path

import numpy as np
from scipy import integrate, optimize

import softfinger as sf

EPS0 = 8.854e-12  # F/m; with mm and MPa: p[MPa] = EPS0 eps_r V^2 / z[mm]^2
#: the film cards' densities, g/cm³ (model/src/material/cards.rs, with their sources)
CARD_RHO = {"VHB-4905": 0.96, "paper-elastic": 0.96, "Elastosil-2030": 1.1}
#: gravity in the bench's second scene: standard, held horizontally curling downward
GRAV, GRAV_DIR = 9.81, 90.0


class ScipyFinger:
    """The three-element model of docs/model.md (m = 1, rigid links, tension alone), in NumPy/SciPy."""

    def __init__(self, p: dict, card: str = "paper-elastic"):
        self.p = p
        n, a, b, t_min, w, e_b = p["n"], p["a"], p["b"], p["t_min"], p["w"], p["e_b"]
        self.n, self.lh, self.e = int(n), 2 * a, p["e"]
        lh = self.lh

        def t(x):  # the elliptical notch's thickness, mm
            return t_min + (b - t_min) * (1 - np.sqrt(max(0.0, 1 - ((x - a) / a) ** 2)))

        def q(f):
            return integrate.quad(f, 0.0, lh, limit=200, epsabs=0, epsrel=1e-12)[0]

        ei = lambda x: e_b * w * t(x) ** 3 / 12
        cxx = q(lambda x: 1 / (e_b * w * t(x)))
        cyy = q(lambda x: (lh - x) ** 2 / ei(x))
        cym = q(lambda x: (lh - x) / ei(x))
        ctt = q(lambda x: 1 / ei(x))
        self.k_hinge = np.linalg.inv(np.array([[cxx, 0, 0], [0, cyy, cym], [0, cym, ctt]]))
        self.e_de = p["e_de"]
        self.g = self.e_de / (2 * (1 + p["nu"]))
        # gravity (docs/model.md "Gravity"): per element, half the hinge and its stack at each
        # of the hinge's ends, the link at its midpoint; forces in N (1 mm³ at 1 g/cm³ = 1e-3 g)
        self.link_len = p["l"] - lh
        notch = lh * t_min + (b - t_min) * (lh - np.pi * a / 2)
        hinge_g = p["rho_b"] * w * notch * 1e-3
        stack_g = CARD_RHO[card] * p["layers"] * p["z0"] * lh * w * 1e-3
        self.half_g, self.link_g = 0.5 * (hinge_g + stack_g), p["rho_b"] * b * w * self.link_len * 1e-3
        d = np.radians(p["grav_dir"])
        self.n_per_g = p["grav"] * 1e-3 * np.array([np.cos(d), np.sin(d)])

    def thickness(self, v: float) -> float:
        """Stack thickness at v volts held until relaxed: the stable root s = z/z0 in
        [4^(-1/3), 1] of the free film's balance G (s - s^4) = eps0 eps_r V^2 / z0^2."""
        p, z0 = self.p, self.p["z0"]
        if v == 0.0:
            return p["layers"] * z0
        rhs = EPS0 * p["eps_r"] * v * v / (z0 * z0)
        s = optimize.brentq(lambda s: self.g * (s - s ** 4) - rhs, 4 ** (-1 / 3), 1.0, xtol=1e-15, rtol=1e-15)
        return p["layers"] * z0 * s

    def compliance(self, v: float) -> np.ndarray:
        """C_k = (C_hinge^-1 + T^T C_de(t)^-1 T)^-1."""
        p, lh = self.p, self.lh
        if p["layers"] == 0:
            return np.linalg.inv(self.k_hinge)
        t = self.thickness(v)
        ea, ei = self.e_de * p["w"] * t, self.e_de * p["w"] * t ** 3 / 12
        c_de = np.array([[lh / ea, 0, 0], [0, lh ** 3 / (3 * ei), lh ** 2 / (2 * ei)], [0, lh ** 2 / (2 * ei), lh / ei]])
        d = p["t_min"] / 2 + t / 2
        T = np.array([[1, 0, d], [0, 1, 0], [0, 0, 1]])
        return np.linalg.inv(self.k_hinge + T.T @ np.linalg.inv(c_de) @ T)

    def weight_loads(self, x: np.ndarray) -> np.ndarray:
        """Each joint's distal weight as a wrench at its hinge's end, in its proximal frame
        (fx, fy, m; N, N·mm): the chain's posture from every joint's q (rigid links)."""
        n, out = self.n, np.zeros((self.n, 3))
        if not self.n_per_g.any():
            return out
        ang, pos, frames, ends, lumps = 0.0, np.zeros(2), [], [], []
        for k in range(n):
            dax, dtr, th = x[3 * k: 3 * k + 3]
            rot = np.array([[np.cos(ang), -np.sin(ang)], [np.sin(ang), np.cos(ang)]])
            end = pos + rot @ np.array([self.lh + dax, dtr])
            a2 = ang + th
            u = np.array([np.cos(a2), np.sin(a2)])
            frames.append(ang)
            ends.append(end)
            # (mass g, where): the hinge's proximal half, its distal half, the link's midpoint
            lumps.append([(self.half_g, pos.copy()), (self.half_g, end), (self.link_g, end + 0.5 * self.link_len * u)])
            pos, ang = end + self.link_len * u, a2
        for k in range(n):
            dist = lumps[k][1:] + [l for j in range(k + 1, n) for l in lumps[j]]
            f = sum(m for m, _ in dist) * self.n_per_g
            mom = sum(m * ((r[0] - ends[k][0]) * self.n_per_g[1] - (r[1] - ends[k][1]) * self.n_per_g[0]) for m, r in dist)
            c, s = np.cos(frames[k]), np.sin(frames[k])
            out[k] = [c * f[0] + s * f[1], -s * f[0] + c * f[1], mom]
        return out

    def residual(self, x: np.ndarray, tension: float, cs) -> np.ndarray:
        """q_k - C_k w_k(q) for every joint: span k's pull on link k's hole (the cable) and the
        weight distal to joint k (which couples the joints)."""
        e, lh = self.e, self.lh
        r = np.empty_like(x)
        wl = self.weight_loads(x)
        for k in range(self.n):
            dax, dtr, th = x[3 * k: 3 * k + 3]
            s, c = np.sin(th), np.cos(th)
            ex, ey = lh + dax, dtr
            hole = np.array([ex - s * e, ey + c * e])
            d = np.array([0.0, e]) - hole
            f = tension * d / np.hypot(d[0], d[1])
            m = (hole[0] - ex) * f[1] - (hole[1] - ey) * f[0]
            r[3 * k: 3 * k + 3] = x[3 * k: 3 * k + 3] - cs[k] @ (np.array([f[0], f[1], m]) + wl[k])
        return r

    def solve(self, tension: float, volts) -> np.ndarray:
        """Joint angles, rad: scipy.optimize.root on the 3n equilibrium equations."""
        cs = [self.compliance(v) for v in volts]
        sol = optimize.root(self.residual, np.zeros(3 * self.n), args=(tension, cs), method="hybr", tol=1e-13)
        if not sol.success:
            raise RuntimeError(sol.message)
        return sol.x[2::3].copy()


def rate(fn, count: int, min_time: float = 1.0) -> float:
    """Solves per second: `fn()` solves `count` postures; repeated for at least `min_time` s."""
    fn()  # warm-up
    n, t0 = 0, time.perf_counter()
    while True:
        fn()
        n += 1
        dt = time.perf_counter() - t0
        if dt >= min_time:
            return n * count / dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--write-docs", action="store_true", help="rewrite the generated table in docs/python.md")
    ap.add_argument("--quick", action="store_true", help="fewer postures (a smoke run)")
    args = ap.parse_args()

    rng = np.random.default_rng(1)
    big = 20_000 if args.quick else 200_000
    P = rng.uniform(0.0, 2.0, big)
    u = rng.uniform(0.0, 0.9, (big, 3))
    n_sci = 100 if args.quick else 1000
    n_loop = 5_000 if args.quick else 50_000
    cores = os.cpu_count()
    table = [
        f"Paper's model (m = 1, rigid links), no tip stiffness; {big:,} postures for `solve_many`, "
        f"{n_loop:,} for the loop, {n_sci:,} for SciPy; {cores} cores ({platform.machine()}, Python {platform.python_version()}). "
        f"Without gravity, and with it (`grav` {GRAV:g} m/s², `grav_dir` {GRAV_DIR:g}: held horizontally, curling downward; the weight couples the joints, "
        "so the SciPy version solves all 3n equations at once either way).",
        "",
        "| gravity | implementation | solves/s | × SciPy |",
        "| --- | --- | ---: | ---: |",
    ]
    notes = []
    for grav in (0.0, GRAV):
        f = sf.Finger(preset="paper_model", grav=grav, grav_dir=GRAV_DIR if grav else 0.0)
        ref = ScipyFinger(f.params, f.card)
        V = u * f.ceiling()
        # the same equilibrium: the SciPy version's angles against the Rust model's
        check = 50
        rust = f.solve_many(P[:check], V[:check], stiffness=False).joints_rad
        sci = np.array([ref.solve(P[i], V[i]) for i in range(check)])
        agree = float(np.max(np.abs(rust - sci)))
        assert agree < 1e-8, f"the SciPy version disagrees with the model by {agree} rad"
        r_scipy = rate(lambda: [ref.solve(P[i], V[i]) for i in range(n_sci)], n_sci)
        r_loop = rate(lambda: [f.solve(P[i], V[i], stiffness=False) for i in range(n_loop)], n_loop)
        r_many = rate(lambda: f.solve_many(P, V, stiffness=False), big)
        default = sf.Finger(preset="default", grav=grav, grav_dir=GRAV_DIR if grav else 0.0)
        r_many_default = rate(lambda: default.solve_many(P[: big // 10], np.minimum(V[: big // 10], 0.9 * default.ceiling()), stiffness=True), big // 10)
        label = f"{grav:g} m/s², {GRAV_DIR:g}°" if grav else "none"
        rows = [
            ("SciPy (scipy.optimize.root per posture, NumPy)", r_scipy, 1.0),
            ("Python loop over `Finger.solve`", r_loop, r_loop / r_scipy),
            ("`Finger.solve_many`", r_many, r_many / r_scipy),
        ]
        table += [f"| {label} | {name} | {r:,.0f} | {x:,.1f} |" for name, r, x in rows]
        notes.append(
            f"{'With' if grav else 'Without'} gravity: the SciPy version's joint angles agree with the model's to {agree:.1e} rad; "
            f"`solve_many` over the loop of `solve`: {r_many / r_loop:,.1f}×; with the default model (m = 8, plate modulus, flexible links) "
            f"and the tip stiffness, `solve_many` does {r_many_default:,.0f} solves/s."
        )
    table += [""] + notes
    text = "\n".join(table)
    print(text)
    if args.write_docs:
        doc = Path(__file__).resolve().parents[2] / "docs" / "python.md"
        s = doc.read_text()
        begin, end = "<!-- BEGIN generated by python/bench/bench_solve_many.py -->", "<!-- END generated -->"
        new, k = re.subn(re.escape(begin) + r".*?" + re.escape(end), lambda _: f"{begin}\n{text}\n{end}", s, flags=re.S)
        assert k == 1, "docs/python.md has no generated-table markers"
        doc.write_text(new)
        print(f"wrote {doc}")


if __name__ == "__main__":
    main()
