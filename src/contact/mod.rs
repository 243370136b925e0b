//! Contact: the rows of slave and master faces — node to node or by dual mortar — with the local
//! frames, nodal areas,
//! slip bounds and initial gaps that define the contact rows N, T of B and the set Λ
//! ([`pairing`]), whether they can hold the bodies held by contact alone under the load
//! ([`hold`]), and the contact state recovered from the dual solution ([`state`]: open /
//! stick / slip, tractions, gaps, slip); the dual mortar coupling of non-matching slave and
//! master faces, with its R*-tree contact search ([`mortar`]).

pub(crate) mod hold;
pub(crate) mod mortar;
pub(crate) mod pairing;
pub mod state;
