//! Rows of variable length stored flat (one list of items and where each row starts): the
//! layout the fused graph operations walk, read in place without one allocation per row.

/// Row `r` is `items[starts[r]..starts[r + 1]]`.
#[derive(Debug)]
pub(super) struct FlatRows<T> {
    pub(super) starts: Vec<usize>,
    pub(super) items: Vec<T>,
}

impl<T> FlatRows<T> {
    /// The rows in order.
    pub(super) fn new(rows: impl IntoIterator<Item = impl IntoIterator<Item = T>>) -> Self {
        let mut starts = vec![0];
        let mut items = Vec::new();
        for row in rows {
            items.extend(row);
            starts.push(items.len());
        }
        Self { starts, items }
    }

    /// The number of rows.
    pub(super) fn len(&self) -> usize {
        self.starts.len() - 1
    }

    /// Row `row`.
    pub(super) fn of(&self, row: usize) -> &[T] {
        &self.items[self.starts[row]..self.starts[row + 1]]
    }
}
