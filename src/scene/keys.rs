//! Every key a scene file may hold, read from the parser's own definitions: the serde structs of
//! [`crate::scene`] (whose `deny_unknown_fields` is the parser's unknown-key check) and the
//! solver settings of [`crate::qp`] (read per method by [`super::SolverSettings::from_table`]).
//!
//! The walk hands each struct's `Deserialize` a deserializer that records the field list serde
//! generated for it — the same list an unknown key is checked against — and the names of every
//! enumerated value, so nothing here repeats a key by hand. `docs/scene-reference.md` is checked
//! against [`keys`] by `tests/scene_reference.rs`, both ways.

use std::cell::RefCell;
use std::collections::BTreeMap;

use serde::de::{self, DeserializeSeed, Deserializer, EnumAccess, IntoDeserializer, MapAccess, SeqAccess, VariantAccess, Visitor};
use serde::Deserialize;

use super::{Friction, Precision, Preconditioner, Scene};
use crate::qp;

/// One key: its dotted path (array-of-tables entries without an index: `body.box.min`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Key {
    /// The dotted path (array-of-tables entries without an index: `body.box.min`).
    pub path: String,
    /// The names an enumerated value takes (empty: not an enumeration).
    pub values: Vec<String>,
    /// `[solver]` keys of one method or a few: the methods that read it (empty: every method).
    pub methods: Vec<String>,
}

/// Every key the scene parser accepts, tables included (`mesh`, `body.box`, …), sorted by path.
pub fn keys() -> Vec<Key> {
    let found = Found::default();
    Scene::deserialize(Tracer::new("", &found)).expect("every scene field has a fixed shape");
    friction(&found, FRICTION);
    // [solver]: the method, the preconditioner, the settings every method reads, each method's own
    let solver = Tracer::new("solver", &found);
    solver.record(&[]);
    let mut methods: Vec<&str> = qp::Method::ALL.iter().map(|m| m.name()).collect();
    methods.push("auto");
    solver.child("method").record(&methods);
    Preconditioner::deserialize(solver.child("preconditioner")).expect("an enumeration");
    Precision::deserialize(solver.child("precision")).expect("an enumeration");
    qp::Common::deserialize(solver.clone()).expect("a struct");
    for m in qp::Method::ALL {
        let own = Found::default();
        qp::MethodParams::deserialize(m, Tracer::new("solver", &own)).expect("a struct");
        for (path, key) in own.into_inner() {
            if path == "solver" {
                continue;
            }
            let mut all = found.borrow_mut();
            let k = all.entry(path).or_insert_with(|| Key { methods: vec![], ..key.clone() });
            k.values = key.values;
            k.methods.push(m.name().to_string());
        }
    }
    found.into_inner().into_values().collect()
}

/// The friction law, an internally tagged enum: serde reads it through a shape-free value, so its
/// variants and their fields are taken from the parser's own messages for an unknown variant and
/// an unknown field (the lists serde checks against).
const FRICTION: &str = "contact.pair.friction";

fn friction(found: &Found, path: &str) {
    let t = Tracer::new(path, found);
    t.record(&[]);
    let probe = |pairs: &[(&str, toml::Value)]| {
        let table: toml::Table = pairs.iter().map(|(k, v)| (k.to_string(), v.clone())).collect();
        Friction::deserialize(toml::Value::Table(table)).err().map(|e| expected(&e.to_string())).unwrap_or_default()
    };
    let variants = probe(&[("type", PROBE.into())]);
    assert!(!variants.is_empty(), "the friction types could not be read from serde's message");
    let names: Vec<&str> = variants.iter().map(String::as_str).collect();
    t.child("type").record(&names);
    for v in &variants {
        for field in probe(&[("type", v.as_str().into()), (PROBE, toml::Value::Integer(0))]) {
            t.child(&field).record(&[]);
        }
    }
}

/// A name no key or variant has.
const PROBE: &str = "\u{1}probe";

/// The names serde lists after "expected" in an unknown-field or unknown-variant message (its
/// first line: the TOML reader adds the key on the next).
fn expected(msg: &str) -> Vec<String> {
    let first = msg.lines().next().unwrap_or_default();
    let Some((_, list)) = first.split_once("expected") else { return vec![] };
    list.split('`').skip(1).step_by(2).map(str::to_string).collect()
}

type Found = RefCell<BTreeMap<String, Key>>;

/// A deserializer that records its path (and an enumeration's names) and hands the visitor a
/// placeholder value of the asked-for shape.
#[derive(Clone)]
struct Tracer<'a> {
    path: String,
    found: &'a Found,
}

impl<'a> Tracer<'a> {
    fn new(path: &str, found: &'a Found) -> Self {
        Tracer { path: path.to_string(), found }
    }

    fn child(&self, name: &str) -> Self {
        let path = if self.path.is_empty() { name.to_string() } else { format!("{}.{name}", self.path) };
        Tracer { path, found: self.found }
    }

    fn record(&self, values: &[&str]) {
        if self.path.is_empty() {
            return;
        }
        let mut found = self.found.borrow_mut();
        let key = found.entry(self.path.clone()).or_insert_with(|| Key { path: self.path.clone(), ..Key::default() });
        for v in values {
            if !key.values.iter().any(|k| k == v) {
                key.values.push(v.to_string());
            }
        }
    }
}

#[derive(Debug)]
struct TraceError(String);

impl std::fmt::Display for TraceError {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for TraceError {}

impl de::Error for TraceError {
    fn custom<T: std::fmt::Display>(msg: T) -> Self {
        TraceError(msg.to_string())
    }
}

macro_rules! leaf {
    ($($method:ident => $visit:ident($($value:expr)?)),* $(,)?) => {
        $(fn $method<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, TraceError> {
            self.record(&[]);
            visitor.$visit($($value)?)
        })*
    };
}

impl<'de> Deserializer<'de> for Tracer<'_> {
    type Error = TraceError;

    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, TraceError> {
        Err(TraceError(format!("{}: read without a fixed shape; describe it in scene::keys like {FRICTION}", self.path)))
    }

    leaf! {
        deserialize_bool => visit_bool(false),
        deserialize_i8 => visit_i64(1), deserialize_i16 => visit_i64(1), deserialize_i32 => visit_i64(1), deserialize_i64 => visit_i64(1),
        deserialize_u8 => visit_u64(1), deserialize_u16 => visit_u64(1), deserialize_u32 => visit_u64(1), deserialize_u64 => visit_u64(1),
        deserialize_f32 => visit_f64(1.0), deserialize_f64 => visit_f64(1.0),
        deserialize_char => visit_char('x'),
        deserialize_str => visit_str("x"), deserialize_string => visit_str("x"),
        deserialize_bytes => visit_bytes(b"x"), deserialize_byte_buf => visit_bytes(b"x"),
        deserialize_unit => visit_unit(),
    }

    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, TraceError> {
        visitor.visit_some(self)
    }

    fn deserialize_unit_struct<V: Visitor<'de>>(self, _: &'static str, visitor: V) -> Result<V::Value, TraceError> {
        self.deserialize_unit(visitor)
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(self, _: &'static str, visitor: V) -> Result<V::Value, TraceError> {
        visitor.visit_newtype_struct(self)
    }

    fn deserialize_seq<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, TraceError> {
        self.deserialize_tuple(1, visitor)
    }

    fn deserialize_tuple<V: Visitor<'de>>(self, len: usize, visitor: V) -> Result<V::Value, TraceError> {
        self.record(&[]);
        visitor.visit_seq(Elements { tracer: self, left: len })
    }

    fn deserialize_tuple_struct<V: Visitor<'de>>(self, _: &'static str, len: usize, visitor: V) -> Result<V::Value, TraceError> {
        self.deserialize_tuple(len, visitor)
    }

    fn deserialize_map<V: Visitor<'de>>(self, _: V) -> Result<V::Value, TraceError> {
        Err(TraceError(format!("{}: a map of free keys; the reference lists fixed keys only", self.path)))
    }

    fn deserialize_struct<V: Visitor<'de>>(self, _: &'static str, fields: &'static [&'static str], visitor: V) -> Result<V::Value, TraceError> {
        self.record(&[]);
        // an internally tagged field is left out here (its struct gives it a default) and walked apart
        let fields: Vec<&'static str> = fields.iter().copied().filter(|f| self.child(f).path != FRICTION).collect();
        visitor.visit_map(Fields { tracer: self, fields, next: 0 })
    }

    fn deserialize_enum<V: Visitor<'de>>(self, _: &'static str, variants: &'static [&'static str], visitor: V) -> Result<V::Value, TraceError> {
        self.record(variants);
        let first = variants.first().ok_or_else(|| TraceError(format!("{}: an enumeration without variants", self.path)))?;
        visitor.visit_enum(Variant(first))
    }

    fn deserialize_identifier<V: Visitor<'de>>(self, _: V) -> Result<V::Value, TraceError> {
        Err(TraceError(format!("{}: an identifier outside a struct or enumeration", self.path)))
    }

    fn deserialize_ignored_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, TraceError> {
        visitor.visit_unit()
    }
}

/// The elements of an array or tuple: `left` placeholders at the array's own path.
struct Elements<'a> {
    tracer: Tracer<'a>,
    left: usize,
}

impl<'de> SeqAccess<'de> for Elements<'_> {
    type Error = TraceError;

    fn next_element_seed<T: DeserializeSeed<'de>>(&mut self, seed: T) -> Result<Option<T::Value>, TraceError> {
        if self.left == 0 {
            return Ok(None);
        }
        self.left -= 1;
        seed.deserialize(self.tracer.clone()).map(Some)
    }
}

/// A struct's fields, each once, each value traced at its own path.
struct Fields<'a> {
    tracer: Tracer<'a>,
    fields: Vec<&'static str>,
    next: usize,
}

impl<'de> MapAccess<'de> for Fields<'_> {
    type Error = TraceError;

    fn next_key_seed<K: DeserializeSeed<'de>>(&mut self, seed: K) -> Result<Option<K::Value>, TraceError> {
        match self.fields.get(self.next) {
            Some(f) => seed.deserialize(IntoDeserializer::<TraceError>::into_deserializer(*f)).map(Some),
            None => Ok(None),
        }
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, TraceError> {
        let field = self.fields[self.next];
        self.next += 1;
        seed.deserialize(self.tracer.child(field))
    }
}

/// An enumeration's first (unit) variant.
struct Variant(&'static str);

impl<'de> EnumAccess<'de> for Variant {
    type Error = TraceError;
    type Variant = Self;

    fn variant_seed<T: DeserializeSeed<'de>>(self, seed: T) -> Result<(T::Value, Self), TraceError> {
        let v = seed.deserialize(IntoDeserializer::<TraceError>::into_deserializer(self.0))?;
        Ok((v, self))
    }
}

impl<'de> VariantAccess<'de> for Variant {
    type Error = TraceError;

    fn unit_variant(self) -> Result<(), TraceError> {
        Ok(())
    }

    fn newtype_variant_seed<T: DeserializeSeed<'de>>(self, _: T) -> Result<T::Value, TraceError> {
        Err(TraceError(format!("variant {}: only unit variants are traced", self.0)))
    }

    fn tuple_variant<V: Visitor<'de>>(self, _: usize, _: V) -> Result<V::Value, TraceError> {
        Err(TraceError(format!("variant {}: only unit variants are traced", self.0)))
    }

    fn struct_variant<V: Visitor<'de>>(self, _: &'static [&'static str], _: V) -> Result<V::Value, TraceError> {
        Err(TraceError(format!("variant {}: only unit variants are traced", self.0)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_cover_the_parser() {
        let keys = keys();
        let has = |p: &str| keys.iter().find(|k| k.path == p);
        for p in
            ["title", "mesh.n", "body.box.sphere.centre", "contact.pair.friction.mu1", "output.fields", "solver.eps", "solver.slide_cap", "tie.search_distance"]
        {
            assert!(has(p).is_some(), "{p} missing");
        }
        assert_eq!(has("solver.slide_cap").unwrap().methods, ["tssn"]);
        assert!(has("solver.eps").unwrap().methods.is_empty());
        assert_eq!(has("contact.pair.friction.type").unwrap().values, ["none", "tresca", "orthotropic", "coulomb"]);
        assert!(has("decomposition.coarse_solve").unwrap().values.contains(&"explicit".to_string()));
    }
}
