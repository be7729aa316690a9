//! A set of vertices as one bit per vertex: the "changed in this pass" set of QEM decimation
//! (Garland & Heckbert, SIGGRAPH 1997; thesis ch. 2.3.2). At 1 bit per vertex it stays
//! cache resident (82 KB for 655k vertices) where the 32-byte vertex records do not, so the
//! many lookups of stale candidates cost no memory traffic.

/// A fixed-size set of vertex ids.
#[derive(Debug, Clone, Default)]
pub(crate) struct VertexBits {
    words: Vec<u64>,
}

impl VertexBits {
    /// The empty set over `n` vertices.
    pub(crate) fn new(n: usize) -> Self {
        Self {
            words: vec![0; n.div_ceil(64)],
        }
    }

    /// Adds `v` (ids beyond the size are ignored).
    #[inline]
    pub(crate) fn insert(&mut self, v: u32) {
        if let Some(w) = self.words.get_mut(v as usize / 64) {
            *w |= 1 << (v % 64);
        }
    }

    /// Removes `v`.
    #[inline]
    pub(crate) fn remove(&mut self, v: u32) {
        if let Some(w) = self.words.get_mut(v as usize / 64) {
            *w &= !(1 << (v % 64));
        }
    }

    /// Whether `v` is in the set.
    #[inline]
    pub(crate) fn contains(&self, v: u32) -> bool {
        self.words
            .get(v as usize / 64)
            .is_some_and(|w| w & (1 << (v % 64)) != 0)
    }

    /// Empties the set.
    pub(crate) fn clear(&mut self) {
        self.words.fill(0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inserts_removes_and_clears() {
        let mut set = VertexBits::new(130);
        for v in [0, 63, 64, 129] {
            assert!(!set.contains(v));
            set.insert(v);
            assert!(set.contains(v));
        }
        assert!(!set.contains(1) && !set.contains(65) && !set.contains(128));
        set.remove(63);
        assert!(!set.contains(63) && set.contains(64));
        set.insert(1000); // out of range: ignored
        assert!(!set.contains(1000));
        set.clear();
        assert!((0..130).all(|v| !set.contains(v)));
    }
}
