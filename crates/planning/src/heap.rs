//! An indexed binary min-heap over node ids with two-part keys `[k1, k2]` compared
//! lexicographically, as D* Lite's priority queue U needs (insert, update, remove, top).
//! Positions live in a flat array indexed by node id: no hash maps.

/// A two-part priority, compared lexicographically.
pub(crate) type Key = [f64; 2];

const ABSENT: u32 = u32::MAX;

#[inline]
fn less(a: Key, b: Key) -> bool {
    a[0] < b[0] || (a[0] == b[0] && a[1] < b[1])
}

/// Indexed min-heap of node ids.
#[derive(Clone, Debug, Default)]
pub(crate) struct IndexedHeap {
    entries: Vec<(Key, u32)>,
    pos: Vec<u32>,
}

impl IndexedHeap {
    /// An empty heap for node ids `0..capacity`.
    pub fn new(capacity: usize) -> Self {
        Self { entries: Vec::new(), pos: vec![ABSENT; capacity] }
    }

    /// Removes every entry (cost proportional to the number of entries).
    pub fn clear(&mut self) {
        for &(_, n) in &self.entries {
            self.pos[n as usize] = ABSENT;
        }
        self.entries.clear();
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// The smallest key, or [inf, inf] when empty.
    #[inline]
    pub fn top_key(&self) -> Key {
        self.entries.first().map_or([f64::INFINITY, f64::INFINITY], |e| e.0)
    }

    /// Removes and returns the node with the smallest key.
    pub fn pop(&mut self) -> Option<(Key, usize)> {
        let top = *self.entries.first()?;
        self.remove_at(0);
        Some((top.0, top.1 as usize))
    }

    /// Inserts the node or changes its key.
    pub fn push_or_update(&mut self, node: usize, key: Key) {
        let p = self.pos[node];
        if p == ABSENT {
            let i = self.entries.len();
            self.entries.push((key, node as u32));
            self.pos[node] = i as u32;
            self.sift_up(i);
        } else {
            let i = p as usize;
            let old = self.entries[i].0;
            self.entries[i].0 = key;
            if less(key, old) {
                self.sift_up(i);
            } else {
                self.sift_down(i);
            }
        }
    }

    /// Removes the node if queued.
    pub fn remove(&mut self, node: usize) {
        let p = self.pos[node];
        if p != ABSENT {
            self.remove_at(p as usize);
        }
    }

    fn remove_at(&mut self, i: usize) {
        let last = self.entries.len() - 1;
        self.pos[self.entries[i].1 as usize] = ABSENT;
        if i != last {
            self.entries.swap(i, last);
            self.entries.pop();
            self.pos[self.entries[i].1 as usize] = i as u32;
            let moved = self.entries[i].0;
            if i > 0 && less(moved, self.entries[(i - 1) / 2].0) {
                self.sift_up(i);
            } else {
                self.sift_down(i);
            }
        } else {
            self.entries.pop();
        }
    }

    fn sift_up(&mut self, mut i: usize) {
        let item = self.entries[i];
        while i > 0 {
            let parent = (i - 1) / 2;
            if !less(item.0, self.entries[parent].0) {
                break;
            }
            self.entries[i] = self.entries[parent];
            self.pos[self.entries[i].1 as usize] = i as u32;
            i = parent;
        }
        self.entries[i] = item;
        self.pos[item.1 as usize] = i as u32;
    }

    fn sift_down(&mut self, mut i: usize) {
        let n = self.entries.len();
        let item = self.entries[i];
        loop {
            let l = 2 * i + 1;
            if l >= n {
                break;
            }
            let r = l + 1;
            let c = if r < n && less(self.entries[r].0, self.entries[l].0) { r } else { l };
            if !less(self.entries[c].0, item.0) {
                break;
            }
            self.entries[i] = self.entries[c];
            self.pos[self.entries[i].1 as usize] = i as u32;
            i = c;
        }
        self.entries[i] = item;
        self.pos[item.1 as usize] = i as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_in_key_order_after_updates_and_removals() {
        let mut h = IndexedHeap::new(10);
        for (n, k) in [(0, 5.0), (1, 3.0), (2, 8.0), (3, 1.0), (4, 3.0)] {
            h.push_or_update(n, [k, n as f64]);
        }
        h.push_or_update(2, [0.5, 0.0]); // decrease
        h.push_or_update(3, [9.0, 0.0]); // increase
        h.remove(0);
        let order: Vec<usize> = std::iter::from_fn(|| h.pop().map(|(_, n)| n)).collect();
        assert_eq!(order, vec![2, 1, 4, 3]);
        assert_eq!(h.len(), 0);
    }
}
