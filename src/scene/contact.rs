//! `[contact]` and `[[tie]]`: contact pairs (faces, discretization, search, press fits),
//! their friction laws, and bonded interfaces.

use serde::{Deserialize, Serialize};

use super::yes;

/// `[contact]`: contact between bodies.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSettings {
    /// `false` drops every contact pair: the bodies are solved as independent elastic problems.
    #[serde(default = "yes")]
    pub enabled: bool,
    /// The `[[contact.pair]]` entries: one slave face against one master face each.
    #[serde(default)]
    pub pair: Vec<ContactPair>,
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings { enabled: true, pair: vec![] }
    }
}

/// One `[[contact.pair]]`: a slave face against a master face, with its friction law.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ContactPair {
    /// The slave face (its nodes carry the multipliers); with `master`, or alone with `faces`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub slave: String,
    /// The master face (another body's); with `slave`, or alone with `faces`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub master: String,
    /// The two faces, where the slave is left to the rule of [`ContactPair::resolve`] (or named
    /// by `slave` or `master` alone).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub faces: Option<[String; 2]>,
    /// The friction law; default frictionless.
    #[serde(default)]
    pub friction: Friction,
    /// Matching tolerance of slave and master node coordinates (m); default 1e-8 × model size.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// `"mortar"` or `"node-to-node"`; default: node-to-node where every slave node has a master
    /// node at its place, mortar otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discretization: Option<Discretization>,
    /// Mortar: how far (m) along its normal a slave facet looks for master facets; default
    /// [`default_search_distance`] of the slave face.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search_distance: Option<f64>,
    /// The largest initial overlap taken as touching, as a fraction of the local element size
    /// (√ of the slave node's area); default [`DEFAULT_MAX_OVERLAP`]. A larger one is an error
    /// unless `interference`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_overlap: Option<f64>,
    /// A press fit: `true`, the bodies overlap as meshed by design and the solution removes the
    /// overlap (any depth within the search distance); a length δ, every slave node of the
    /// pair starts δ inside the master whatever the meshed gap (two faceted meshes of one
    /// curved face differ by their chords' sagittas).
    #[serde(default, skip_serializing_if = "Fit::is_none")]
    pub interference: Fit,
}

/// `contact.pair.interference`: none, as meshed (`true`), or a stated radial interference δ.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Fit {
    /// `false` (the default): no press fit.
    #[default]
    None,
    /// `true`: the bodies overlap as meshed by design and the solution removes the overlap.
    Meshed,
    /// A length δ (m): every slave node of the pair starts δ inside the master, whatever the
    /// meshed gap.
    Stated(f64),
}

impl Fit {
    /// Whether there is no press fit (`interference = false`).
    pub fn is_none(&self) -> bool {
        *self == Fit::None
    }

    /// Whether the bodies may overlap as meshed.
    pub fn allows_overlap(&self) -> bool {
        !self.is_none()
    }
}

impl Serialize for Fit {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match *self {
            Fit::None => s.serialize_bool(false),
            Fit::Meshed => s.serialize_bool(true),
            Fit::Stated(d) => s.serialize_f64(d),
        }
    }
}

impl<'de> Deserialize<'de> for Fit {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Fit;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("true, false or an interference length")
            }
            fn visit_bool<E: serde::de::Error>(self, b: bool) -> std::result::Result<Fit, E> {
                Ok(if b { Fit::Meshed } else { Fit::None })
            }
            fn visit_f64<E: serde::de::Error>(self, x: f64) -> std::result::Result<Fit, E> {
                Ok(Fit::Stated(x))
            }
            fn visit_i64<E: serde::de::Error>(self, x: i64) -> std::result::Result<Fit, E> {
                Ok(Fit::Stated(x as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, x: u64) -> std::result::Result<Fit, E> {
                Ok(Fit::Stated(x as f64))
            }
        }
        d.deserialize_f64(V)
    }
}

/// The default largest initial overlap taken as touching: 10⁻³ of the local element size
/// (bodies meshed touching overlap by round-off and by the facets' chords: 10⁻⁶–10⁻⁴ h).
pub const DEFAULT_MAX_OVERLAP: f64 = 1e-3;

/// How a contact or tied interface is discretized.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Discretization {
    /// Dual mortar (biorthogonal multipliers on the slave face): any two meshes.
    Mortar,
    /// One pair per slave node and the master node at its place: matching meshes only.
    NodeToNode,
}

/// The default mortar search distance: a tenth of the slave face's bounding-box diagonal.
pub fn default_search_distance(diagonal: f64) -> f64 {
    0.1 * diagonal
}

/// A bonded interface: the slave face's displacement equals the master face's, weakly (the
/// mortar projection), in all three directions.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Tie {
    /// The slave face (`body.face`).
    pub slave: String,
    /// The master face (`body.face`, not the slave).
    pub master: String,
    /// As for contact pairs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search_distance: Option<f64>,
}

/// Friction law of a contact pair.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum Friction {
    /// `none`: frictionless (the default).
    #[default]
    None,
    /// Isotropic Tresca with slip bound g (MPa).
    Tresca {
        /// Tresca slip bound (MPa), ≥ 0.
        g: f64,
    },
    /// Orthotropic Tresca: slip bounds g1 along `direction` (projected onto the contact plane),
    /// g2 across it.
    Orthotropic {
        /// Slip bound along `direction` (MPa), ≥ 0.
        g1: f64,
        /// Slip bound across `direction` (MPa), ≥ 0.
        g2: f64,
        /// Projected onto the contact plane: the first tangent (non-zero).
        direction: [f64; 3],
    },
    /// Coulomb: ‖λτ,ᵢ‖ ≤ μ λν,ᵢ (`mu`), or orthotropic with `mu1` along `direction` and `mu2`
    /// across it; solved as a fixed point on the slip bounds (`qp::coulomb`).
    Coulomb {
        /// Isotropic Coulomb coefficient μ, ≥ 0; either `mu`, or `mu1`, `mu2` and `direction`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mu: Option<f64>,
        /// Orthotropic Coulomb coefficient along `direction`, ≥ 0.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mu1: Option<f64>,
        /// Orthotropic Coulomb coefficient across `direction`, ≥ 0.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mu2: Option<f64>,
        /// With `mu1`: projected onto the contact plane, the first tangent (non-zero).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        direction: Option<[f64; 3]>,
    },
}

impl Friction {
    /// The direction the pair's first tangent follows, when the law has one.
    pub fn direction(&self) -> Option<[f64; 3]> {
        match *self {
            Friction::Orthotropic { direction, .. } => Some(direction),
            Friction::Coulomb { direction, .. } => direction,
            _ => None,
        }
    }
}
