//! `[[face]]`: named faces cut out of existing ones by a region (box, ball, cylinder,
//! half-space).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// `name` becomes the face `<body>.<name>`: the facets of `<body>.<from>` whose centres lie in
/// one region: the box `[min, max]`, a ball, an infinite cylinder, or a half-space.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FaceDef {
    /// The new face's name (non-empty, no `.`).
    pub name: String,
    /// The body.
    pub body: String,
    /// The face of that body cut from.
    pub from: String,
    /// Lower corner of the selecting box (m); with `max`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<[f64; 3]>,
    /// Upper corner of the selecting box (m); with `min`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<[f64; 3]>,
    /// A ball region.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere: Option<SphereRegion>,
    /// An infinite cylinder region.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cylinder: Option<CylinderRegion>,
    /// A half-space region.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub half_space: Option<HalfSpaceRegion>,
}

/// The points within `radius` of `centre`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SphereRegion {
    /// The ball's centre (m).
    pub centre: [f64; 3],
    /// Its radius (m), > 0.
    pub radius: f64,
}

/// The points within `radius` of the line through `point` along `axis`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CylinderRegion {
    /// A point of the axis (m).
    pub point: [f64; 3],
    /// The axis direction (nonzero; its length does not matter).
    pub axis: [f64; 3],
    /// Its radius (m), > 0.
    pub radius: f64,
}

/// The points on the side of the plane through `point` that `normal` points to (the plane
/// included).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HalfSpaceRegion {
    /// A point of the plane (m).
    pub point: [f64; 3],
    /// The plane's normal (nonzero), pointing to the side kept.
    pub normal: [f64; 3],
}

/// The region a `[[face]]` selects from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Region {
    /// The box between its lower and upper corners (`face.min`, `face.max`).
    Box([f64; 3], [f64; 3]),
    /// A ball (`face.sphere`).
    Sphere(SphereRegion),
    /// An infinite cylinder (`face.cylinder`).
    Cylinder(CylinderRegion),
    /// A half-space (`face.half_space`).
    HalfSpace(HalfSpaceRegion),
}

impl Region {
    /// Whether `x` lies in the region (its boundary included, to 10⁻¹² of its size for the
    /// round ones).
    pub fn contains(&self, x: [f64; 3]) -> bool {
        let d = |a: [f64; 3], b: [f64; 3]| -> [f64; 3] { std::array::from_fn(|k| a[k] - b[k]) };
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        match *self {
            Region::Box(lo, hi) => (0..3).all(|k| x[k] >= lo[k] && x[k] <= hi[k]),
            Region::Sphere(s) => dot(d(x, s.centre), d(x, s.centre)).sqrt() <= s.radius * (1.0 + 1e-12),
            Region::Cylinder(c) => {
                let a = c.axis.map(|v| v / dot(c.axis, c.axis).sqrt());
                let r = d(x, c.point);
                let along = dot(r, a);
                (dot(r, r) - along * along).max(0.0).sqrt() <= c.radius * (1.0 + 1e-12)
            }
            Region::HalfSpace(h) => {
                let n = h.normal.map(|v| v / dot(h.normal, h.normal).sqrt());
                let scale = dot(h.point, h.point).sqrt().max(dot(x, x).sqrt());
                dot(d(x, h.point), n) >= -1e-12 * scale
            }
        }
    }

    /// "the box […]", "the sphere of radius r about c", …, for messages.
    pub fn describe(&self) -> String {
        let v = |a: [f64; 3]| format!("({}, {}, {})", a[0], a[1], a[2]);
        match self {
            Region::Box(lo, hi) => format!("the box {} – {}", v(*lo), v(*hi)),
            Region::Sphere(s) => format!("the ball of radius {} about {}", s.radius, v(s.centre)),
            Region::Cylinder(c) => format!("the cylinder of radius {} about the axis {} through {}", c.radius, v(c.axis), v(c.point)),
            Region::HalfSpace(h) => format!("the half-space through {} on the side of {}", v(h.point), v(h.normal)),
        }
    }
}

impl FaceDef {
    /// The region it selects from; `i` its index, for the error (exactly one region, each
    /// value finite, radii > 0, directions nonzero).
    pub fn region(&self, i: usize) -> Result<Region> {
        let key = |k: &str| format!("face[{i}].{k}");
        let finite =
            |k: &str, v: &[f64]| if v.iter().all(|x| x.is_finite()) { Ok(()) } else { Err(Error::scene(key(k), format!("must be finite, got {v:?}"))) };
        let positive = |k: &str, r: f64| if r.is_finite() && r > 0.0 { Ok(()) } else { Err(Error::scene(key(k), format!("must be > 0, got {r}"))) };
        let nonzero = |k: &str, v: [f64; 3]| {
            finite(k, &v)?;
            let l = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if l > 0.0 && l.is_finite() {
                Ok(())
            } else {
                Err(Error::scene(key(k), format!("must be a nonzero direction, got {v:?}")))
            }
        };
        let given = [self.min.is_some() || self.max.is_some(), self.sphere.is_some(), self.cylinder.is_some(), self.half_space.is_some()];
        if given.iter().filter(|&&g| g).count() != 1 {
            return Err(Error::scene(format!("face[{i}]"), "give exactly one region: `min` and `max` (a box), `sphere`, `cylinder` or `half_space`"));
        }
        if given[0] {
            let (Some(lo), Some(hi)) = (self.min, self.max) else {
                return Err(Error::scene(key(if self.min.is_none() { "min" } else { "max" }), "a box needs both `min` and `max`"));
            };
            finite("min", &lo)?;
            finite("max", &hi)?;
            return Ok(Region::Box(lo, hi));
        }
        if let Some(s) = self.sphere {
            finite("sphere.centre", &s.centre)?;
            positive("sphere.radius", s.radius)?;
            return Ok(Region::Sphere(s));
        }
        if let Some(c) = self.cylinder {
            finite("cylinder.point", &c.point)?;
            nonzero("cylinder.axis", c.axis)?;
            positive("cylinder.radius", c.radius)?;
            return Ok(Region::Cylinder(c));
        }
        let h = self.half_space.expect("one region is given");
        finite("half_space.point", &h.point)?;
        nonzero("half_space.normal", h.normal)?;
        Ok(Region::HalfSpace(h))
    }
}
