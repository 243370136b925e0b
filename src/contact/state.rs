//! Recovery of the contact state from the dual solution: per pair the status (open / stick /
//! slip, or in contact where the pair has no friction), the normal and tangential tractions, the current gap and the slip, and the node fields
//! that carry them into the result file.
//!
//! With r = Aλ − b = −(Bu − c): the current gap is rν,ᵢ = dᵢ − (Nu)ᵢ ≥ 0 and the relative
//! tangential displacement (slip) is ūτ,ᵢ = −r̄τ,ᵢ. The slave node receives the force
//! −(λν,ᵢ nᵢ + λτ,₁ t₁ᵢ + λτ,₂ t₂ᵢ); tractions are forces divided by the nodal area wᵢ.

use crate::contact::pairing::Contact;
use crate::output::{Center, Field, Values};
use crate::qp::lambda::Lambda;
use crate::qp::sets::ConvexSet;

/// Status codes written to the `contact_status` field (0 on nodes without a contact pair).
pub const OPEN: i32 = 1;
/// Closed pair with friction that sticks.
pub const STICK: i32 = 2;
/// Closed pair with friction that slips (λ̄τ on the slip bound, or sliding: [`contact_state`]).
pub const SLIP: i32 = 3;
/// Closed, on a pair without friction (neither stick nor slip).
pub const CONTACT: i32 = 4;

/// The contact state of every pair.
#[derive(Clone, Debug, Default)]
pub struct ContactState {
    /// Status of each pair: [`OPEN`], [`STICK`], [`SLIP`] or [`CONTACT`].
    pub status: Vec<i32>,
    /// Normal multiplier λν,ᵢ (force, ≥ 0).
    pub normal_force: Vec<f64>,
    /// Tangential multiplier as a global vector λτ,₁t₁ + λτ,₂t₂.
    pub tangential_force: Vec<[f64; 3]>,
    /// Current gap (≥ 0 up to the solver tolerance).
    pub gap: Vec<f64>,
    /// Relative tangential displacement of the slave w.r.t. the master node, global vector.
    pub slip: Vec<[f64; 3]>,
    /// Closed pairs with ‖λ̄τ,ᵢ‖ on the slip bound: the slipping pairs but those an ε-hair
    /// inside it that slide (see [`contact_state`]).
    pub on_slip_bound: usize,
}

impl ContactState {
    /// Number of pairs with status `status`.
    pub fn count(&self, status: i32) -> usize {
        self.status.iter().filter(|&&s| s == status).count()
    }

    /// Total force the contact exerts on the slave bodies.
    pub fn total_force(&self, contact: &Contact) -> [f64; 3] {
        let mut f = [0.0; 3];
        for i in 0..contact.len() {
            for c in 0..3 {
                f[c] -= self.normal_force[i] * contact.normal[i][c] + self.tangential_force[i][c];
            }
        }
        f
    }
}

/// Classifies each pair from λ and r = Aλ − b; `tol` is relative (to the largest λν, at least
/// `force`, the problem's force scale (`pipeline::accuracy::force_scale`; 0: none), and to gᵢ).
/// A closed pair slips when λ̄τ is on the bound (within `tol`), or when it is better explained
/// as sliding than as sticking: its relative distance to the bound (along the ray through λ̄τ)
/// is smaller than its relative slip ‖r̄τ‖/‖b‖ (`bnorm`) — the same comparison as the KKT
/// friction-law residual, so that a sliding pair an ε-hair inside the bound is not called stuck.
pub fn contact_state(contact: &Contact, set: &Lambda, lambda: &[f64], r: &[f64], tol: f64, bnorm: f64, force: f64) -> ContactState {
    let m = contact.len();
    let lmax = lambda[..m].iter().fold(0.0f64, |a, v| a.max(*v)).max(if force.is_finite() { force } else { 0.0 });
    let mut s = ContactState::default();
    for i in 0..m {
        let (lt, rt) = if set.layout.friction {
            let k = set.layout.tangent(i, 0);
            ([lambda[k], lambda[k + 1]], [r[k], r[k + 1]])
        } else {
            ([0.0; 2], [0.0; 2])
        };
        let global = |v: [f64; 2]| -> [f64; 3] { std::array::from_fn(|c| v[0] * contact.t1[i][c] + v[1] * contact.t2[i][c]) };
        let on_bound = set.layout.friction && {
            // ‖λ̄τ‖ on the boundary: scaling it up by (1 + tol) leaves the set
            let out = [lt[0] * (1.0 + tol), lt[1] * (1.0 + tol)];
            set.tangent[i].is_outside(&out) && lt != [0.0, 0.0]
        };
        let sliding = set.layout.friction && lt != [0.0, 0.0] && {
            let t = set.tangent[i].max_step(&lt, &[-lt[0], -lt[1]]);
            t / (1.0 + t) < rt[0].hypot(rt[1]) / bnorm.max(f64::MIN_POSITIVE)
        };
        let closed = lambda[i] > tol * lmax;
        s.on_slip_bound += usize::from(closed && on_bound && contact.has_friction_at(i));
        s.status.push(if !closed {
            OPEN
        } else if !contact.has_friction_at(i) {
            CONTACT
        } else if on_bound || sliding {
            SLIP
        } else {
            STICK
        });
        s.normal_force.push(lambda[i]);
        s.tangential_force.push(global(lt));
        s.gap.push(r[i]);
        s.slip.push(global([-rt[0], -rt[1]]));
    }
    s
}

/// Node fields of the contact state on the slave nodes of the pairs `pairs` (a field's values
/// in their order; the other nodes are zero in the result file), and those nodes: the rows of
/// every field, as for a distributed field ([`crate::output::OutputData::rows`]).
pub fn contact_fields(contact: &Contact, state: &ContactState, pairs: &[usize], want: impl Fn(&str) -> bool) -> (Vec<Field>, Vec<usize>) {
    let mut fields = Vec::new();
    let scalar = |name: &str, f: &dyn Fn(usize) -> f64| Field {
        name: name.into(),
        center: Center::Node,
        ncomp: 1,
        values: Values::F64(pairs.iter().map(|&i| f(i)).collect()),
    };
    let vector = |name: &str, f: &dyn Fn(usize) -> [f64; 3]| Field {
        name: name.into(),
        center: Center::Node,
        ncomp: 3,
        values: Values::F64(pairs.iter().flat_map(|&i| f(i)).collect()),
    };
    if want("contact_status") {
        fields.push(Field {
            name: "contact_status".into(),
            center: Center::Node,
            ncomp: 1,
            values: Values::I32(pairs.iter().map(|&i| state.status[i]).collect()),
        });
    }
    if want("contact_pressure") {
        fields.push(scalar("contact_pressure", &|i| state.normal_force[i] / contact.area[i]));
    }
    if want("contact_traction") {
        fields.push(vector("contact_traction", &|i| state.tangential_force[i].map(|f| f / contact.area[i])));
    }
    if want("contact_pressure_smooth") || want("contact_traction_smooth") {
        let p: Vec<[f64; 1]> = (0..contact.len()).map(|i| [state.normal_force[i] / contact.area[i]]).collect();
        let t: Vec<[f64; 3]> = (0..contact.len()).map(|i| state.tangential_force[i].map(|f| f / contact.area[i])).collect();
        let (ps, ts) = (contact.smooth(&p), contact.smooth(&t));
        if want("contact_pressure_smooth") {
            fields.push(scalar("contact_pressure_smooth", &|i| ps[i][0]));
        }
        if want("contact_traction_smooth") {
            fields.push(vector("contact_traction_smooth", &|i| ts[i]));
        }
    }
    if want("gap") {
        fields.push(scalar("gap", &|i| state.gap[i]));
    }
    if want("slip") {
        fields.push(vector("slip", &|i| state.slip[i]));
    }
    (fields, pairs.iter().map(|&i| contact.slave[i]).collect())
}
