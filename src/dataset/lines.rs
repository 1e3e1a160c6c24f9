//! Where each data row of a CSV file is: the map from row index to file line that the reader
//! builds and the checks ([`super::validate`]) name lines with. Its own module so that the
//! reader and the checks do not import each other.

/// Where each data row is in the file: rows are consecutive lines except after skipped
/// (blank or comment) lines, recorded as jumps.
pub(super) struct LineMap {
    /// `(row index, line)` at the first row and wherever a row does not follow the previous
    /// row's line directly; increasing in both.
    pub(super) jumps: Vec<(usize, usize)>,
}

impl LineMap {
    pub(super) fn push(&mut self, row: usize, line: usize) {
        match self.jumps.last() {
            Some(&(r, l)) if l + (row - r) == line => {}
            _ => self.jumps.push((row, line)),
        }
    }

    pub(super) fn line_of(&self, row: usize) -> usize {
        let k = self.jumps.partition_point(|&(r, _)| r <= row);
        match k.checked_sub(1).and_then(|k| self.jumps.get(k)) {
            Some(&(r, l)) => l + (row - r),
            None => 0,
        }
    }
}
