//! File tags (node labels) to file indices: a vector indexed by tag − smallest tag where the
//! tags are dense (the usual numbering 1…n, with a few gaps), a hash map where they are sparse.

use rustc_hash::FxHashMap;

/// Where a tag is absent from the dense vector.
const ABSENT: usize = usize::MAX;

/// The file index of every tag.
pub(crate) enum TagIndex {
    /// `at[tag − min]` (or [`ABSENT`]).
    Dense { min: u64, at: Vec<usize> },
    /// Tags too spread for a vector.
    Sparse(FxHashMap<u64, usize>),
}

impl TagIndex {
    /// Tag `tags[i]` → `i`; `Err(i)` at the first tag listed a second time (position `i`).
    pub(crate) fn new(tags: &[u64]) -> Result<Self, usize> {
        let (Some(&min), Some(&max)) = (tags.iter().min(), tags.iter().max()) else {
            return Ok(TagIndex::Dense { min: 0, at: Vec::new() });
        };
        // a vector of at most twice the tags (plus a little) costs no more than the map would
        let span = max - min;
        if span < 2 * tags.len() as u64 + 1024 {
            let mut at = vec![ABSENT; span as usize + 1];
            for (i, &t) in tags.iter().enumerate() {
                let slot = &mut at[(t - min) as usize];
                if *slot != ABSENT {
                    return Err(i);
                }
                *slot = i;
            }
            return Ok(TagIndex::Dense { min, at });
        }
        let mut map = FxHashMap::with_capacity_and_hasher(tags.len(), Default::default());
        for (i, &t) in tags.iter().enumerate() {
            if map.insert(t, i).is_some() {
                return Err(i);
            }
        }
        Ok(TagIndex::Sparse(map))
    }

    /// Tags `1…n` (Exodus, MED: nodes numbered from one) → `0…n−1`.
    pub(crate) fn one_based(n: usize) -> Self {
        TagIndex::Dense { min: 1, at: (0..n).collect() }
    }

    /// The file index of `tag`, if the file defines it.
    #[inline]
    pub(crate) fn get(&self, tag: u64) -> Option<usize> {
        match self {
            TagIndex::Dense { min, at } => {
                let i = at.get(usize::try_from(tag.checked_sub(*min)?).ok()?).copied()?;
                (i != ABSENT).then_some(i)
            }
            TagIndex::Sparse(map) => map.get(&tag).copied(),
        }
    }

    /// Whether the file defines `tag`.
    pub(crate) fn contains(&self, tag: u64) -> bool {
        self.get(tag).is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::TagIndex;
    use std::collections::HashMap;

    /// Both layouts answer as a plain hash map of the same tags does, absent tags included.
    #[test]
    fn dense_and_sparse_agree_with_a_map() {
        let dense: Vec<u64> = (0..500u64).map(|i| 1 + (i * 7919) % 600).collect::<std::collections::BTreeSet<_>>().into_iter().rev().collect();
        let sparse: Vec<u64> = (0..500u64).map(|i| 3 + i * i * 1_000_003).collect();
        for (tags, want_dense) in [(&dense, true), (&sparse, false)] {
            let index = TagIndex::new(tags).unwrap();
            assert_eq!(matches!(index, TagIndex::Dense { .. }), want_dense);
            let map: HashMap<u64, usize> = tags.iter().enumerate().map(|(i, &t)| (t, i)).collect();
            for t in (0..700u64).chain(tags.iter().copied()).chain([u64::MAX, u64::MAX - 1]) {
                assert_eq!(index.get(t), map.get(&t).copied(), "tag {t}");
            }
        }
        assert!(TagIndex::one_based(3).get(0).is_none() && TagIndex::one_based(3).get(3) == Some(2) && !TagIndex::one_based(3).contains(4));
    }

    /// A tag listed twice is found at its second place, dense or sparse.
    #[test]
    fn repeated_tag_is_an_error_at_its_second_place() {
        assert_eq!(TagIndex::new(&[5, 6, 7, 6, 8]).err(), Some(3));
        assert_eq!(TagIndex::new(&[5, 1 << 40, 7, 1 << 40]).err(), Some(3));
        assert!(TagIndex::new(&[]).unwrap().get(0).is_none());
    }
}
