//! The links reversed: for every target, the positions in a flat link list that point to it,
//! in increasing order (a counting sort). The backward passes of the fused graph operations
//! use it to gather, per row they own, what a forward scatter would have added, so that they
//! run in parallel without races and add in a fixed order.

use super::flat_rows::FlatRows;

/// Links reversed for `count` targets; entries `≥ count` (empty slots) are skipped.
pub(super) struct IncomingLinks(FlatRows<u32>);

impl IncomingLinks {
    /// Reverses `links` (`links[p]`: the target of position `p`).
    pub(super) fn new(links: &[u32], count: usize) -> Self {
        let mut starts = vec![0usize; count + 1];
        for &l in links {
            if (l as usize) < count {
                starts[l as usize + 1] += 1;
            }
        }
        for i in 0..count {
            starts[i + 1] += starts[i];
        }
        let mut positions = vec![0u32; starts[count]];
        let mut next = starts.clone();
        for (p, &l) in links.iter().enumerate() {
            let l = l as usize;
            if l < count {
                positions[next[l]] = p as u32;
                next[l] += 1;
            }
        }
        Self(FlatRows {
            starts,
            items: positions,
        })
    }

    /// The positions whose link points to `target`, increasing.
    pub(super) fn of(&self, target: usize) -> &[u32] {
        self.0.of(target)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_link_is_listed_under_its_target_in_order() {
        let links = [2u32, 0, 2, 5, 1, 2];
        let incoming = IncomingLinks::new(&links, 3);
        assert_eq!(incoming.of(0), &[1]);
        assert_eq!(incoming.of(1), &[4]);
        assert_eq!(incoming.of(2), &[0, 2, 5]);
    }
}
