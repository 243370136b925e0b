//! Parts, instances and the assembly of an Abaqus input, as Abaqus/CAE writes them: each
//! `*INSTANCE, NAME=i, PART=p` … `*END INSTANCE` places a copy of part `p`'s nodes, elements,
//! sets and surfaces (`i.set`, `i.surface`; the element set `i` holds all its elements), moved
//! by the instance's data lines: the first a translation (x, y, z), the second a rotation
//! (point a, point b, angle in degrees about the axis a→b, right-handed), the translation
//! applied before the rotation (Abaqus Keywords Reference, `*INSTANCE`). Labels are per part:
//! instance `k` (from 1) holds its part's label `L` as `k·2⁴⁰ + L`, shown as `i.L` in messages;
//! assembly-level sets and surfaces name them `i.L` or `i.set`, or give `INSTANCE=i`.

use std::collections::HashSet;

use super::{fields, float, param, Deck, Elem, Fail, Surface, SurfaceItem, Ty};
use crate::mesh::{Cell, Facet};

/// Bits of an instance label that hold the part's own label.
const SHIFT: u32 = 40;

/// The label instance `k` (from 1) gives its part's label `l`.
pub(super) fn shifted(k: usize, l: u64) -> u64 {
    ((k as u64) << SHIFT) | l
}

/// The label a set item names, if it names one: `L` (of instance `instance`, if given) or
/// `i.L` (of instance `i`); `None` for a set name.
pub(super) fn resolve(f: &str, instance: Option<usize>, names: &[String]) -> Option<u64> {
    if let Ok(l) = f.parse::<u64>() {
        return Some(instance.map_or(l, |k| shifted(k, l)));
    }
    let (inst, rest) = f.split_once('.')?;
    let k = names.iter().position(|n| n.eq_ignore_ascii_case(inst))? + 1;
    rest.parse::<u64>().ok().map(|l| shifted(k, l))
}

/// An `*INSTANCE` being read: its name, part, line and data lines.
struct Placing {
    name: String,
    part: String,
    line: usize,
    data: Vec<(Vec<f64>, usize)>,
}

/// The part or instance the lines at hand are inside.
#[derive(Default)]
pub(super) struct Nest {
    /// The deck outside the `*PART` being read, the part's name and line.
    outer: Option<(Deck, String, usize)>,
    placing: Option<Placing>,
    /// The instance placed last, to be closed by `*END INSTANCE`.
    placed: Option<usize>,
}

impl Nest {
    /// A data line of `*INSTANCE` (translation, then rotation).
    pub(super) fn data_line(&mut self, t: &str, i: usize) -> Result<(), Fail> {
        let Some(p) = self.placing.as_mut() else { return Ok(()) };
        let v = fields(t).map(|f| float(f, i)).collect::<Result<Vec<f64>, Fail>>()?;
        let want = [3, 7].get(p.data.len()).ok_or_else(|| Fail::at(i, format!("*INSTANCE {}: more than two data lines (translation; rotation)", p.name)))?;
        if v.len() != *want {
            let what = if p.data.is_empty() { "translation x, y, z" } else { "rotation: point a, point b, angle in degrees" };
            return Err(Fail::at(i, format!("*INSTANCE {}: {} numbers where the {what} takes {want}", p.name, v.len())));
        }
        p.data.push((v, i));
        Ok(())
    }

    /// At the end of the input: every part and instance closed.
    pub(super) fn finish(&self) -> Result<(), Fail> {
        if let Some((_, name, at)) = &self.outer {
            return Err(Fail::at(*at, format!("*PART {name} has no *END PART")));
        }
        if let Some(p) = &self.placing {
            return Err(Fail::at(p.line, format!("*INSTANCE {} has no *END INSTANCE", p.name)));
        }
        Ok(())
    }
}

/// The rigid motion of an instance's data lines: x ↦ R (x + t − a) + a.
fn motion(p: &Placing) -> Result<impl Fn([f64; 3]) -> [f64; 3], Fail> {
    let t = p.data.first().map_or([0.0; 3], |(v, _)| [v[0], v[1], v[2]]);
    let rot = match p.data.get(1) {
        None => None,
        Some((v, at)) => {
            let (a, b) = ([v[0], v[1], v[2]], [v[3], v[4], v[5]]);
            let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if len == 0.0 || !len.is_finite() {
                return Err(Fail::at(*at, format!("*INSTANCE {}: the rotation axis has a = b", p.name)));
            }
            let n = d.map(|x| x / len);
            let th = v[6].to_radians();
            Some((a, n, th.cos(), th.sin()))
        }
    };
    Ok(move |x: [f64; 3]| {
        let y = [x[0] + t[0], x[1] + t[1], x[2] + t[2]];
        let Some((a, n, c, s)) = rot else { return y };
        // Rodrigues: v cos θ + (n × v) sin θ + n (n·v)(1 − cos θ)
        let v = [y[0] - a[0], y[1] - a[1], y[2] - a[2]];
        let nv = n[0] * v[0] + n[1] * v[1] + n[2] * v[2];
        let cr = [n[1] * v[2] - n[2] * v[1], n[2] * v[0] - n[0] * v[2], n[0] * v[1] - n[1] * v[0]];
        std::array::from_fn(|d| a[d] + v[d] * c + cr[d] * s + n[d] * nv * (1.0 - c))
    })
}

impl Deck {
    /// Handles the keywords of parts, instances and the assembly; false for any other.
    pub(super) fn structure(&mut self, name: &str, params: &[(String, String)], i: usize, nest: &mut Nest) -> Result<bool, Fail> {
        let named = |key: &str| param(params, key).map(str::to_string).ok_or_else(|| Fail::at(i, format!("*{name} without {key}=")));
        match name {
            "PART" => {
                if let Some((_, p, at)) = &nest.outer {
                    return Err(Fail::at(i, format!("*PART inside *PART {p} (line {} of the input has no *END PART)", at + 1)));
                }
                let part = named("NAME")?;
                nest.outer = Some((std::mem::take(self), part, i));
            }
            "END PART" => {
                let (outer, part, _) = nest.outer.take().ok_or_else(|| Fail::at(i, "*END PART without *PART"))?;
                let deck = std::mem::replace(self, outer);
                self.parts.insert(part.to_ascii_uppercase(), (part, deck));
            }
            "INSTANCE" => {
                if nest.outer.is_some() || nest.placing.is_some() {
                    return Err(Fail::at(i, "*INSTANCE inside a *PART or another *INSTANCE"));
                }
                let (inst, part) = (named("NAME")?, named("PART")?);
                nest.placing = Some(Placing { name: inst, part, line: i, data: Vec::new() });
            }
            "END INSTANCE" => {
                if let Some(p) = nest.placing.take() {
                    nest.placed = Some(self.place(p)?);
                } else if nest.placed.take().is_none() {
                    return Err(Fail::at(i, "*END INSTANCE without *INSTANCE"));
                }
            }
            "ASSEMBLY" | "END ASSEMBLY" => {}
            _ => {
                if let Some(p) = nest.placing.take() {
                    // an instance's data ends at its first keyword (a mesh inside it is not read)
                    nest.placed = Some(self.place(p)?);
                }
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// The instance that `INSTANCE=` names (its number from 1), if any.
    pub(super) fn instance_param(&self, params: &[(String, String)], i: usize) -> Result<Option<usize>, Fail> {
        let Some(inst) = param(params, "INSTANCE") else { return Ok(None) };
        let k = self
            .instances
            .iter()
            .position(|n| n.eq_ignore_ascii_case(inst))
            .ok_or_else(|| Fail::at(i, format!("INSTANCE={inst} names no instance defined before (instances: {})", list(&self.instances))))?;
        Ok(Some(k + 1))
    }

    /// A label for messages: `i.L` for instance `i`'s label `L`.
    pub(super) fn show(&self, l: u64) -> String {
        match (l >> SHIFT) as usize {
            0 => l.to_string(),
            k => format!("{}.{}", self.instances.get(k - 1).map_or("?", String::as_str), l & ((1 << SHIFT) - 1)),
        }
    }

    /// Places a copy of the part `p` names; returns the instance's number.
    fn place(&mut self, p: Placing) -> Result<usize, Fail> {
        let (part_name, part) = self.parts.get(&p.part.to_ascii_uppercase()).ok_or_else(|| {
            let known: Vec<String> = self.parts.values().map(|(n, _)| n.clone()).collect();
            Fail::at(p.line, format!("*INSTANCE {}: part \"{}\" is not defined before it (parts: {})", p.name, p.part, list(&known)))
        })?;
        if !part.elems.iter().any(|e| matches!(e.ty, Ty::Cell(_) | Ty::Solid)) {
            return Err(Fail::at(p.line, format!("*INSTANCE {}: part \"{part_name}\" has no volume elements", p.name)));
        }
        if self.instances.iter().any(|n| n.eq_ignore_ascii_case(&p.name)) {
            return Err(Fail::at(p.line, format!("instance \"{}\" is defined twice", p.name)));
        }
        let k = self.instances.len() + 1;
        let (inst, moved) = (p.name.clone(), motion(&p)?);
        let mut copy = Deck::default();
        for (l, x) in &part.nodes {
            let at = part.node_line[l];
            if *l >> SHIFT != 0 {
                return Err(Fail::at(at, format!("node label {l} of a part is too large (at most {})", (1u64 << SHIFT) - 1)));
            }
            copy.node_line.insert(shifted(k, *l), at);
            copy.nodes.push((shifted(k, *l), moved(*x)));
        }
        for e in &part.elems {
            if let Some(n) = e.nodes.iter().find(|n| !part.node_line.contains_key(n)).filter(|_| matches!(e.ty, Ty::Cell(_))) {
                return Err(Fail::at(e.line, format!("element {} of part {part_name} refers to node {n}, which no *NODE of the part defines", e.label)));
            }
            copy.elem_index.insert(shifted(k, e.label), copy.elems.len());
            let nodes = e.nodes.iter().map(|&n| shifted(k, n)).collect();
            copy.elems.push(Elem { label: shifted(k, e.label), ty: e.ty, type_name: e.type_name.clone(), nodes, line: e.line });
        }
        copy.elsets.entry(&inst).extend(copy.elems.iter().filter(|e| matches!(e.ty, Ty::Cell(_) | Ty::Solid)).map(|e| e.label));
        for s in &part.elsets.list {
            copy.elsets.entry(&format!("{inst}.{}", s.name)).extend(s.labels.iter().map(|&l| shifted(k, l)));
        }
        for s in &part.nsets.list {
            copy.nsets.entry(&format!("{inst}.{}", s.name)).extend(s.labels.iter().map(|&l| shifted(k, l)));
        }
        for s in &part.surfaces {
            let items = s.items.iter().map(|it| SurfaceItem { what: format!("{inst}.{}", it.what), face: it.face, line: it.line }).collect();
            copy.surfaces.push(Surface { name: format!("{inst}.{}", s.name), node: s.node, items });
        }
        self.instances.push(inst);
        self.merge(copy);
        Ok(k)
    }

    /// Adds an instance's copy (its labels are its own: no clash).
    fn merge(&mut self, copy: Deck) {
        let base = self.elems.len();
        self.node_line.extend(copy.node_line);
        self.nodes.extend(copy.nodes);
        self.elem_index.extend(copy.elem_index.into_iter().map(|(l, e)| (l, e + base)));
        self.elems.extend(copy.elems);
        for s in copy.elsets.list {
            self.elsets.entry(&s.name).extend(s.labels);
        }
        for s in copy.nsets.list {
            self.nsets.entry(&s.name).extend(s.labels);
        }
        self.surfaces.extend(copy.surfaces);
    }

    /// The facets of node surface `s`: the body's boundary facets whose nodes all lie in it.
    pub(super) fn node_surface(
        &self,
        s: &Surface,
        cells: &[Cell],
        boundary: &super::super::topology::Boundary,
        to_local: &dyn Fn(&u64) -> Option<usize>,
    ) -> Result<Vec<Facet>, Fail> {
        let mut set = HashSet::new();
        for item in &s.items {
            let labels = match resolve(&item.what, None, &self.instances) {
                Some(l) => vec![l],
                None => {
                    let set = self.nsets.get(&item.what);
                    set.ok_or_else(|| Fail::at(item.line, format!("*SURFACE {} names node set \"{}\", which is not defined", s.name, item.what)))?
                        .labels
                        .clone()
                }
            };
            for l in labels {
                if !self.node_line.contains_key(&l) {
                    return Err(Fail::at(item.line, format!("*SURFACE {} names node {}, which no *NODE defines", s.name, self.show(l))));
                }
                set.extend(to_local(&l));
            }
        }
        Ok(crate::mesh::topology::facets_on_nodes(cells, boundary, &set))
    }
}

/// Names in quotes, comma-separated ("none" when empty).
fn list(names: &[String]) -> String {
    if names.is_empty() {
        return "none".into();
    }
    names.iter().map(|n| format!("\"{n}\"")).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_about_an_axis_after_the_translation() {
        // translate by (1, 0, 0), then 90° about the z axis through (0, 0, 0)-(0, 0, 1):
        // (1, 0, 0) → (2, 0, 0) → (0, 2, 0); (0, 1, 5) → (1, 1, 5) → (-1, 1, 5)
        let p = Placing { name: "i".into(), part: "p".into(), line: 0, data: vec![(vec![1.0, 0.0, 0.0], 1), (vec![0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 90.0], 2)] };
        let Ok(m) = motion(&p) else { panic!("no motion") };
        for (x, want) in [([1.0, 0.0, 0.0], [0.0, 2.0, 0.0]), ([0.0, 1.0, 5.0], [-1.0, 1.0, 5.0])] {
            let y = m(x);
            assert!((0..3).all(|d| (y[d] - want[d]).abs() < 1e-14), "{x:?} → {y:?}, want {want:?}");
        }
        // 120° about the diagonal (1, 1, 1) through the origin permutes the axes: x → y → z
        let p = Placing { data: vec![(vec![0.0; 3], 1), (vec![0.0, 0.0, 0.0, 2.0, 2.0, 2.0, 120.0], 2)], ..p };
        let Ok(m) = motion(&p) else { panic!("no motion") };
        let y = m([3.0, 0.0, 0.0]);
        assert!((y[0]).abs() < 1e-14 && (y[1] - 3.0).abs() < 1e-14 && y[2].abs() < 1e-14, "{y:?}");
        let p = Placing { data: vec![(vec![0.0; 3], 1), (vec![1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 30.0], 2)], ..p };
        assert!(motion(&p).is_err());
    }
}
