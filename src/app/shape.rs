//! `shape <P> <V1> <V2> <V3>` (a console addition, docs/firmware.md): the posture `solve`
//! computes, as drawable geometry. Model only, nothing moves; the arguments are checked as
//! `solve` checks them. Reply `ok nodes=x,y,deg,.. hinges=x,y,deg,.. thick=t1,t2,t3`:
//! `nodes` the n + 1 node poses (node 0 the clamp, node n the tip), `hinges` each hinge's
//! distal end (where link k starts), mm and degrees in the base frame.

use finger_model::Method;
use finger_protocol::field;

use super::commands::Commands;
use super::errors::{model_err, CmdError};
use super::help::{list, Reply, Tip};
use super::params::CHANNELS;

impl Commands {
    #[inline(never)]
    pub(super) fn cmd_shape(&self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        let (p, v) = self.model_request(args, "shape <P> <V1> <V2> <V3>")?;
        let sol = self.planner.finger().solve(p, &v, Method::converged()).map_err(model_err)?;
        let link_len = self.planner.finger().params().l - self.planner.finger().params().hinge_len();
        let _ = w!(r; field::NODES.first());
        for k in 0..=CHANNELS {
            pose(r, k > 0, &sol.nodes[k]);
        }
        let _ = w!(r; field::HINGES.after());
        for k in 0..CHANNELS {
            // link k's proximal end: node k+1 taken back along the link's own deflection
            let (n1, q) = (sol.nodes[k + 1], sol.links[k]);
            let theta = n1.theta - q[2];
            let (s, c) = finger_model::Real::sin_cos(theta);
            let dx = link_len + q[0];
            let start = finger_model::Pose { x: n1.x - (c * dx - s * q[1]), y: n1.y - (s * dx + c * q[1]), theta };
            pose(r, k > 0, &start);
        }
        let _ = w!(r; field::THICK.after());
        list(r, &sol.thickness[..CHANNELS], 4);
        Ok(())
    }
}

fn pose(r: &mut Reply, comma: bool, p: &finger_model::Pose<f32>) {
    if comma {
        let _ = w!(r; ",");
    }
    let _ = w!(r; Tip(p));
}
