//! Compressed sparse rows.

/// A list of lists in two flat arrays: the items of row `i` are
/// `items[offsets[i]..offsets[i + 1]]`.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Csr {
    /// Row starts, `rows + 1` entries.
    pub offsets: Vec<u32>,
    /// Items of all rows, concatenated.
    pub items: Vec<u32>,
}

impl Csr {
    /// Builds rows from `(row, item)` pairs; within a row, items keep the order
    /// in which they were given (a counting sort, so stable and deterministic).
    pub fn from_pairs<I>(rows: usize, pairs: I) -> Self
    where
        I: IntoIterator<Item = (usize, u32)> + Clone,
    {
        let mut offsets = vec![0u32; rows + 1];
        for (r, _) in pairs.clone() {
            offsets[r + 1] += 1;
        }
        for i in 0..rows {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut items = vec![0u32; offsets[rows] as usize];
        for (r, item) in pairs {
            items[fill[r] as usize] = item;
            fill[r] += 1;
        }
        Self { offsets, items }
    }

    /// The lists with some rows worked out again: `rows` rows, row `i`
    /// copied from `self` unless `i` is in `replaced` (ascending, no
    /// repeats), whose rows `row(i, out)` appends to `out` instead. Rows
    /// from `self.rows()` on must all be replaced (they have nothing to
    /// copy). A topology change touches a few rows of the node→element
    /// lists: copying the rest costs a pass over the items, against the
    /// counting sort of every pair that [`Csr::from_pairs`] does.
    pub fn with_rows_replaced(&self, rows: usize, replaced: &[u32], mut row: impl FnMut(u32, &mut Vec<u32>)) -> Self {
        let mut offsets = Vec::with_capacity(rows + 1);
        let mut items = Vec::with_capacity(self.items.len() + 8 * replaced.len());
        offsets.push(0);
        let mut next = replaced.iter().copied().peekable();
        let mut i = 0;
        while i < rows {
            if next.peek() == Some(&(i as u32)) {
                next.next();
                row(i as u32, &mut items);
                offsets.push(items.len() as u32);
                i += 1;
                continue;
            }
            // a run of copied rows up to the next replaced one: one copy
            let end = next.peek().map_or(rows, |&r| r as usize);
            assert!(end <= self.rows(), "row {} is new and must be replaced", self.rows().max(i));
            let (from, to) = (self.offsets[i], self.offsets[end]);
            items.extend_from_slice(&self.items[from as usize..to as usize]);
            let shift = items.len() as i64 - to as i64;
            offsets.extend(self.offsets[i + 1..=end].iter().map(|&o| (o as i64 + shift) as u32));
            i = end;
        }
        Self { offsets, items }
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// The items of row `i`.
    #[inline(always)]
    pub fn row(&self, i: usize) -> &[u32] {
        &self.items[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_keep_insertion_order() {
        let c = Csr::from_pairs(3, vec![(2, 7), (0, 1), (2, 3), (0, 9)]);
        assert_eq!(c.row(0), &[1, 9]);
        assert_eq!(c.row(1), &[] as &[u32]);
        assert_eq!(c.row(2), &[7, 3]);
        assert_eq!(c.rows(), 3);
    }

    #[test]
    fn replaced_rows_match_a_build_from_scratch() {
        let c = Csr::from_pairs(5, vec![(0, 1), (1, 2), (1, 3), (3, 4), (4, 5), (4, 6)]);
        // rows 1 and 3 replaced, two new rows (5, 6) appended
        let got = c.with_rows_replaced(7, &[1, 3, 5, 6], |i, out| out.extend((0..i).map(|k| 10 * i + k)));
        let kept = [(0, 1), (4, 5), (4, 6)];
        let made = [(1, 10)].into_iter().chain((0..3).map(|k| (3, 30 + k)));
        let appended = (0..5).map(|k| (5, 50 + k)).chain((0..6).map(|k| (6, 60 + k)));
        let mut pairs: Vec<(usize, u32)> = kept.into_iter().chain(made).chain(appended).collect();
        pairs.sort_unstable();
        let want = Csr::from_pairs(7, pairs);
        assert_eq!(got, want);
        // nothing replaced: a copy
        assert_eq!(c.with_rows_replaced(5, &[], |_, _| {}), c);
    }
}
