//! Gravity, a forcing (docs/model.md "Gravity"): the finger's weight, lumped per element, and
//! the load it puts on each joint's distal chain and on each link. What it is not: a solver
//! (the coupled solve, `loaded`, carries the distal centroids as unknowns) or an equation of the
//! sub-element (gravity reaches the march as an external load, `TipLoad`, like a tip force).
//!
//! The lumps of element k: the hinge with its stack, half at each of the hinge's ends (its
//! proximal end is node k-1), and the link at its midpoint, on the centreline. Masses in g,
//! forces in N.

use super::{Finger, Heading, JointState, TipLoad, HELD};
use crate::params::{MAX_JOINTS, MAX_SUB};
use crate::real::Real;

/// Proximal frames, hinge ends and weight lumps of a chain (`Finger::chain_at_posture`).
pub(super) type ChainAtPosture<R> = ([Heading<R>; MAX_JOINTS], [Heading<R>; MAX_JOINTS], [[[R; 2]; 3]; MAX_JOINTS]);

/// The finger's weight: the lumps' masses (g) and gravity's force per gram (N/g, base frame).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Weights<R> {
    /// Half of one hinge with its stack, g (at each of the hinge's ends).
    pub half_hinge_g: R,
    /// One link, g (at its midpoint).
    pub link_g: R,
    /// Gravity's force on one gram, N, base frame: grav · 1e-3 · (cos, sin) of grav_dir.
    pub n_per_g: [R; 2],
}

/// Where a chain puts the lumps of each element (base frame, mm): the hinge's proximal end
/// (node k-1), its distal end and the link's midpoint.
pub(crate) type Lumps<R> = [[[R; 2]; 3]; MAX_JOINTS];

impl<R: Real> Weights<R> {
    /// The weight carried distal to joint k's sub-elements (0-based), N: the hinge's distal
    /// half, the link and every element beyond.
    pub fn joint_load(&self, n: usize, k: usize) -> [R; 2] {
        let beyond = R::from_u32((n - 1 - k) as u32);
        let el = self.half_hinge_g + self.half_hinge_g + self.link_g;
        self.force(self.half_hinge_g + self.link_g + beyond * el)
    }

    /// Gravity's force on `grams`, N (base frame).
    pub fn force(&self, grams: R) -> [R; 2] {
        [self.n_per_g[0] * grams, self.n_per_g[1] * grams]
    }

    /// The centroid of each joint's distal lumps (`joint_load`'s mass), base frame, from where
    /// a chain puts the lumps.
    pub fn centroids(&self, n: usize, lumps: &Lumps<R>) -> [[R; 2]; MAX_JOINTS] {
        let mut out = [[R::zero(); 2]; MAX_JOINTS];
        let (mut sx, mut sy, mut mass) = (R::zero(), R::zero(), R::zero());
        for k in (0..n).rev() {
            let [prox, end, mid] = lumps[k];
            sx += self.half_hinge_g * end[0] + self.link_g * mid[0];
            sy += self.half_hinge_g * end[1] + self.link_g * mid[1];
            mass += self.half_hinge_g + self.link_g;
            out[k] = [sx / mass, sy / mass];
            sx += self.half_hinge_g * prox[0];
            sy += self.half_hinge_g * prox[1];
            mass += self.half_hinge_g;
        }
        out
    }
}

impl<R: Real> Finger<R> {
    /// The finger's weight, or None without gravity (`Params::has_gravity`).
    ///
    /// Hinge volume: w ∫ t(x) dx over the notch, `t` of `hinge::notch_thickness`, in closed form
    /// 2a t_min + (b - t_min)(2a - πa/2); the stack: N_L z0 L_h w of the card's film (its volume
    /// is kept as it thins); the link: b w (l - L_h). 1 mm³ at 1 g/cm³ is 1e-3 g.
    pub(crate) fn weights(&self) -> Option<Weights<R>> {
        let p = &self.p;
        if !p.has_gravity() {
            return None;
        }
        let milli = R::from_f64(1e-3);
        let two_a = p.hinge_len();
        let notch = two_a * p.t_min + (p.b - p.t_min) * (two_a - R::from_f64(core::f64::consts::FRAC_PI_2) * p.a);
        let hinge_g = p.rho_b * p.w * notch * milli;
        let stack_g = R::from_f64(p.card.rho_g_cm3) * R::from_u32(p.layers) * p.z0 * two_a * p.w * milli;
        let link_g = p.rho_b * p.b * p.w * self.link_len * milli;
        let dir = p.grav_dir * R::from_f64(core::f64::consts::PI / 180.0);
        let g = p.grav * milli;
        let (s, c) = R::sin_cos(dir);
        Some(Weights { half_hinge_g: R::from_f64(0.5) * (hinge_g + stack_g), link_g, n_per_g: [g * c, g * s] })
    }

    /// The lumps of element k (0-based) for its proximal frame `node` (node k-1) and its
    /// hinge's end `hinge_end` (base frame).
    pub(crate) fn lumps_of(&self, node: &Heading<R>, hinge_end: &Heading<R>) -> [[R; 2]; 3] {
        let mid = hinge_end.then(R::from_f64(0.5) * self.link_len, R::zero(), R::zero());
        [[node.pose.x, node.pose.y], [hinge_end.pose.x, hinge_end.pose.y], [mid.pose.x, mid.pose.y]]
    }

    /// The distal centroids (`Weights::centroids`) of a chain given by each joint's proximal
    /// frame `nodes[k]` and its states' hinge ends.
    pub(super) fn centroids_of_chain(&self, w: &Weights<R>, nodes: &[Heading<R>], states: &[JointState<R>; MAX_JOINTS]) -> [[R; 2]; MAX_JOINTS] {
        let mut lumps = [[[R::zero(); 2]; 3]; MAX_JOINTS];
        for k in 0..self.p.n {
            let e = states[k].end;
            lumps[k] = self.lumps_of(&nodes[k], &nodes[k].then(e.x, e.y, e.theta));
        }
        w.centroids(self.p.n, &lumps)
    }

    /// The base-frame load on link k (0-based) besides the cable: the tip force at `tip`, the
    /// weight beyond it (joint k+1's at its centroid `beyond`, and the next hinge's proximal half
    /// at the link's end) and its own at its midpoint. None if there is none.
    pub(super) fn link_load(&self, k: usize, hinge_end: &Heading<R>, tip: Option<([R; 2], [R; 2])>, w: Option<(&Weights<R>, R, [R; 2])>) -> Option<TipLoad<R>> {
        let n = self.p.n;
        let mut load = tip.map(|(f, t)| TipLoad::at(f, t));
        if let Some((w, scale, beyond)) = w {
            let end = hinge_end.then(self.link_len, R::zero(), R::zero());
            let mid = hinge_end.then(R::from_f64(0.5) * self.link_len, R::zero(), R::zero());
            let mut add = |force: [R; 2], at: [R; 2]| {
                let force = [force[0] * scale, force[1] * scale];
                load = Some(match load {
                    Some(l) => l.plus(force, at),
                    None => TipLoad::at(force, at),
                });
            };
            add(w.force(w.link_g), [mid.pose.x, mid.pose.y]);
            if k + 1 < n {
                add(w.force(w.half_hinge_g), [end.pose.x, end.pose.y]);
                add(w.joint_load(n, k + 1), beyond);
            }
        }
        load
    }

    /// The base-frame load on joint k's (0-based) distal chain besides the cable: the tip force
    /// at `tip` and the distal weight (scaled by `scale`, the load continuation's factor) at its
    /// centroid `centroid`.
    pub(super) fn joint_ext_load(&self, k: usize, tip: Option<([R; 2], [R; 2])>, w: Option<(&Weights<R>, R, [R; 2])>) -> Option<TipLoad<R>> {
        let load = tip.map(|(f, t)| TipLoad::at(f, t));
        match w {
            Some((w, scale, centroid)) => {
                let g = w.joint_load(self.p.n, k);
                let g = [g[0] * scale, g[1] * scale];
                Some(match load {
                    Some(l) => l.plus(g, centroid),
                    None => TipLoad::at(g, centroid),
                })
            }
            None => load,
        }
    }
}

impl<R: Real> Finger<R> {
    /// Whether gravity acts on this finger (docs/model.md "Gravity").
    pub fn has_weight(&self) -> bool {
        self.weights().is_some()
    }

    /// The chain at a posture of sub-element displacements `sub_q` and link deflections `links`:
    /// each joint's proximal frame, its hinge's distal end and the weight's lumps there (base
    /// frame; the walk of `weight_at_posture`, the tip compliance's weight term and the
    /// equilibrium residual).
    pub(super) fn chain_at_posture(&self, sub_q: &[[[R; 3]; MAX_SUB]; MAX_JOINTS], links: &[[R; 3]; MAX_JOINTS]) -> ChainAtPosture<R> {
        let mut nodes = [Heading::origin(); MAX_JOINTS];
        let mut ends = [Heading::origin(); MAX_JOINTS];
        let mut lumps = [[[R::zero(); 2]; 3]; MAX_JOINTS];
        let mut node = Heading::origin();
        for k in 0..self.p.n {
            let e = self.walk(&sub_q[k]).pose;
            let hinge_end = node.then(e.x, e.y, e.theta);
            lumps[k] = self.lumps_of(&node, &hinge_end);
            (nodes[k], ends[k]) = (node, hinge_end);
            let l = links[k];
            node = hinge_end.then(self.link_len + l[0], l[1], l[2]);
        }
        (nodes, ends, lumps)
    }

    /// The weight's load on each joint (its proximal frame) and the wrench it adds on each link
    /// (the link's frame) at the posture of sub-element displacements `sub_q` and link
    /// deflections `links`: the inverse's fixed loads (`held`).
    pub(crate) fn weight_at_posture(&self, sub_q: &[[[R; 3]; MAX_SUB]; MAX_JOINTS], links: &[[R; 3]; MAX_JOINTS]) -> HeldLoads<R> {
        let n = self.p.n;
        let mut held = [None; HELD];
        let mut held_link = [[R::zero(); 3]; HELD];
        let Some(w) = self.weights() else { return (held, held_link) };
        let (nodes, ends, lumps) = self.chain_at_posture(sub_q, links);
        let c = w.centroids(n, &lumps);
        for (k, (h, hl)) in held.iter_mut().zip(held_link.iter_mut()).enumerate().take(n) {
            let g = Some((&w, R::one(), c[k]));
            *h = self.joint_ext_load(k, None, g).map(|l| Self::load_in_frame(&nodes[k], l));
            let beyond = Some((&w, R::one(), c[(k + 1).min(n - 1)]));
            if let Some(l) = self.link_load(k, &ends[k], None, beyond) {
                let with = self.link_wrench(R::zero(), Some((&ends[k], l)));
                let without = self.link_wrench(R::zero(), None);
                *hl = [with[0] - without[0], with[1] - without[1], with[2] - without[2]];
            }
        }
        (held, held_link)
    }

    /// Joint k's (0-based) linear turn under its held load alone, rad: the load's moment about
    /// the joint's proximal end times the sub-elements' rotational compliances (0 without one).
    pub(crate) fn held_turn(&self, k: usize, c: &[crate::mat3::Mat3<R>; MAX_SUB]) -> R {
        match self.held.get(k).copied().flatten() {
            Some(l) => {
                let moment = l.point[0] * l.force[1] - l.point[1] * l.force[0] + l.couple;
                moment * c[..self.p.m].iter().fold(R::zero(), |a, m| a + m[2][2])
            }
            None => R::zero(),
        }
    }

    /// Whether joints k and j (0-based) carry the same held loads (always without any): only
    /// then may a solve take one's state for the other's.
    pub(crate) fn same_held(&self, k: usize, j: usize) -> bool {
        self.held.get(k) == self.held.get(j) && self.held_link.get(k) == self.held_link.get(j)
    }

    /// Whether this finger carries fixed loads (`holding`).
    pub(crate) fn has_held(&self) -> bool {
        self.held.iter().any(|h| h.is_some())
    }

    /// This finger without gravity, carrying `loads` as fixed loads instead (the inverse's:
    /// every per-joint solve then sees the weight at that posture).
    pub(crate) fn holding(&self, loads: &HeldLoads<R>) -> Finger<R> {
        let mut f = *self;
        f.p.grav = R::zero();
        (f.held, f.held_link) = *loads;
        f
    }
}

/// Each joint's fixed load and each link's added wrench (`Finger::weight_at_posture`).
pub(crate) type HeldLoads<R> = ([Option<TipLoad<R>>; HELD], [[R; 3]; HELD]);
