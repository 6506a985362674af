//! An indexed binary min-heap over node ids with two-part keys `[k1, k2]` compared
//! lexicographically, as D* Lite's priority queue U needs (insert, update, remove, top), and the
//! open list of A*. Positions live in a flat array indexed by node id: no hash maps.
//!
//! Layout, chosen for speed without changing which node comes out first (the planners' paths
//! among equal-cost alternatives depend on it): each key is packed into one `u128` whose
//! unsigned order is the lexicographic `<` order of the two `f64`s ([`pack`]), so a comparison
//! is one branch-free integer compare; keys and node ids are separate arrays, 1-based so two
//! siblings share half a cache line; `pop` moves the hole to a leaf along the smaller children
//! and then lifts the last entry back up (Floyd's bottom-up sift-down), one comparison per
//! level instead of two. Every step does exactly what the textbook heap does, including among
//! equal keys: a child replaces its parent only when strictly smaller, the right child is
//! taken only when strictly smaller than the left, and the sift-up stops below an equal key.
//! The test compares the pop order with a textbook heap under many ties.

/// A two-part priority, compared lexicographically.
pub(crate) type Key = [f64; 2];

const ABSENT: u32 = u32::MAX;

/// The order-preserving integer image of one `f64` (any value but NaN): `a < b` exactly when
/// `bits(a) < bits(b)`; -0 maps as +0, so they stay equal as under `<`.
#[inline(always)]
fn bits(x: f64) -> u64 {
    debug_assert!(!x.is_nan(), "NaN heap key");
    let b = (x + 0.0).to_bits();
    if b >> 63 == 1 { !b } else { b | (1 << 63) }
}

#[inline(always)]
fn unbits(b: u64) -> f64 {
    f64::from_bits(if b >> 63 == 1 { b & !(1 << 63) } else { !b })
}

/// A key packed so that `pack(a) < pack(b)` exactly when `a[0] < b[0] || (a[0] == b[0] && a[1] <
/// b[1])`.
#[inline(always)]
fn pack(k: Key) -> u128 {
    ((bits(k[0]) as u128) << 64) | bits(k[1]) as u128
}

#[inline(always)]
fn unpack(p: u128) -> Key {
    [unbits((p >> 64) as u64), unbits(p as u64)]
}

/// Indexed min-heap of node ids.
#[derive(Clone, Debug)]
pub(crate) struct IndexedHeap {
    /// Packed keys; slot 0 unused, the root at 1, children of `i` at `2i` and `2i + 1`.
    keys: Vec<u128>,
    /// Node id per slot (slot 0 unused).
    nodes: Vec<u32>,
    /// Slot per node id, or `ABSENT`.
    pos: Vec<u32>,
}

impl Default for IndexedHeap {
    fn default() -> Self {
        Self::new(0)
    }
}

impl IndexedHeap {
    /// An empty heap for node ids `0..capacity`.
    pub fn new(capacity: usize) -> Self {
        Self { keys: vec![0], nodes: vec![0], pos: vec![ABSENT; capacity] }
    }

    /// Removes every entry (cost proportional to the number of entries).
    pub fn clear(&mut self) {
        for &n in &self.nodes[1..] {
            self.pos[n as usize] = ABSENT;
        }
        self.keys.truncate(1);
        self.nodes.truncate(1);
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.keys.len() - 1
    }

    /// The smallest key, or [inf, inf] when empty.
    #[inline]
    pub fn top_key(&self) -> Key {
        self.keys.get(1).map_or([f64::INFINITY, f64::INFINITY], |&p| unpack(p))
    }

    /// Removes and returns the node with the smallest key.
    #[inline]
    pub fn pop(&mut self) -> Option<(Key, usize)> {
        let n = self.len();
        if n == 0 {
            return None;
        }
        let (key, node) = (self.keys[1], self.nodes[1]);
        self.pos[node as usize] = ABSENT;
        let (last_key, last_node) = (self.keys[n], self.nodes[n]);
        self.keys.truncate(n);
        self.nodes.truncate(n);
        if n > 1 {
            self.sift_down_from_root(last_key, last_node);
        }
        Some((unpack(key), node as usize))
    }

    /// Inserts the node or changes its key.
    #[inline]
    pub fn push_or_update(&mut self, node: usize, key: Key) {
        let key = pack(key);
        let p = self.pos[node];
        if p == ABSENT {
            self.keys.push(key);
            self.nodes.push(node as u32);
            self.sift_up(self.keys.len() - 1, key, node as u32);
        } else {
            let i = p as usize;
            if key < self.keys[i] {
                self.sift_up(i, key, node as u32);
            } else {
                self.sift_down(i, key, node as u32);
            }
        }
    }

    /// Removes the node if queued.
    pub fn remove(&mut self, node: usize) {
        let p = self.pos[node];
        if p == ABSENT {
            return;
        }
        let i = p as usize;
        self.pos[node] = ABSENT;
        let last = self.len();
        let (key, moved) = (self.keys[last], self.nodes[last]);
        self.keys.truncate(last);
        self.nodes.truncate(last);
        if i != last {
            if i > 1 && key < self.keys[i / 2] {
                self.sift_up(i, key, moved);
            } else {
                self.sift_down(i, key, moved);
            }
        }
    }

    /// Puts `(key, node)` into the hole at slot `i` and moves it up while strictly smaller than
    /// its parent.
    #[inline(always)]
    fn sift_up(&mut self, mut i: usize, key: u128, node: u32) {
        while i > 1 {
            let parent = i / 2;
            let pk = self.keys[parent];
            if key >= pk {
                break;
            }
            self.keys[i] = pk;
            let pn = self.nodes[parent];
            self.nodes[i] = pn;
            self.pos[pn as usize] = i as u32;
            i = parent;
        }
        self.keys[i] = key;
        self.nodes[i] = node;
        self.pos[node as usize] = i as u32;
    }

    /// Puts `(key, node)` into the hole at slot `i` and moves it down while a child is strictly
    /// smaller (the textbook sift-down, for updates and removals).
    fn sift_down(&mut self, mut i: usize, key: u128, node: u32) {
        let n = self.len();
        loop {
            let l = 2 * i;
            if l > n {
                break;
            }
            let c = if l < n && self.keys[l + 1] < self.keys[l] { l + 1 } else { l };
            let ck = self.keys[c];
            if ck >= key {
                break;
            }
            self.keys[i] = ck;
            let cn = self.nodes[c];
            self.nodes[i] = cn;
            self.pos[cn as usize] = i as u32;
            i = c;
        }
        self.keys[i] = key;
        self.nodes[i] = node;
        self.pos[node as usize] = i as u32;
    }

    /// The textbook sift-down of `(key, node)` from the root, done bottom-up: the hole goes to a
    /// leaf along the smaller children (the right one only when strictly smaller), then the
    /// entry rises while its parent is not smaller than it. It ends in the slot where the
    /// textbook loop stops (above the first path entry that is not smaller than it), with the
    /// same entries moved.
    #[inline(always)]
    fn sift_down_from_root(&mut self, key: u128, node: u32) {
        let n = self.len();
        let keys = &mut self.keys[..=n];
        let nodes = &mut self.nodes[..=n];
        let mut i = 1;
        loop {
            let l = 2 * i;
            if l >= n {
                if l == n {
                    keys[i] = keys[l];
                    let ln = nodes[l];
                    nodes[i] = ln;
                    self.pos[ln as usize] = i as u32;
                    i = l;
                }
                break;
            }
            let c = l + usize::from(keys[l + 1] < keys[l]);
            keys[i] = keys[c];
            let cn = nodes[c];
            nodes[i] = cn;
            self.pos[cn as usize] = i as u32;
            i = c;
        }
        while i > 1 {
            let parent = i / 2;
            let pk = keys[parent];
            if pk < key {
                break;
            }
            keys[i] = pk;
            let pn = nodes[parent];
            nodes[i] = pn;
            self.pos[pn as usize] = i as u32;
            i = parent;
        }
        keys[i] = key;
        nodes[i] = node;
        self.pos[node as usize] = i as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

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

    #[test]
    fn packed_order_is_lexicographic_float_order() {
        let v = [
            f64::NEG_INFINITY,
            -3.5,
            -1e-300,
            -0.0,
            0.0,
            1e-300,
            0.5,
            1.0,
            2.0f64.sqrt(),
            7e300,
            f64::INFINITY,
        ];
        for &a0 in &v {
            for &a1 in &v {
                for &b0 in &v {
                    for &b1 in &v {
                        let textbook = a0 < b0 || (a0 == b0 && a1 < b1);
                        assert_eq!(pack([a0, a1]) < pack([b0, b1]), textbook, "{a0} {a1} {b0} {b1}");
                    }
                }
                let [u0, u1] = unpack(pack([a0, a1]));
                assert!(u0 == a0 && u1 == a1);
            }
        }
    }

    /// The textbook indexed binary heap (0-based, float keys, top-down sift-down): the order
    /// the planners' paths were first recorded with.
    #[derive(Default)]
    struct Textbook {
        entries: Vec<(Key, usize)>,
    }

    fn less(a: Key, b: Key) -> bool {
        a[0] < b[0] || (a[0] == b[0] && a[1] < b[1])
    }

    impl Textbook {
        fn find(&self, node: usize) -> Option<usize> {
            self.entries.iter().position(|e| e.1 == node)
        }
        fn push_or_update(&mut self, node: usize, key: Key) {
            match self.find(node) {
                None => {
                    self.entries.push((key, node));
                    self.up(self.entries.len() - 1);
                }
                Some(i) => {
                    let old = self.entries[i].0;
                    self.entries[i].0 = key;
                    if less(key, old) { self.up(i) } else { self.down(i) }
                }
            }
        }
        fn remove_at(&mut self, i: usize) {
            let last = self.entries.len() - 1;
            self.entries.swap(i, last);
            self.entries.pop();
            if i < last {
                if i > 0 && less(self.entries[i].0, self.entries[(i - 1) / 2].0) {
                    self.up(i)
                } else {
                    self.down(i)
                }
            }
        }
        fn up(&mut self, mut i: usize) {
            while i > 0 && less(self.entries[i].0, self.entries[(i - 1) / 2].0) {
                self.entries.swap(i, (i - 1) / 2);
                i = (i - 1) / 2;
            }
        }
        fn down(&mut self, mut i: usize) {
            let n = self.entries.len();
            loop {
                let l = 2 * i + 1;
                if l >= n {
                    return;
                }
                let r = l + 1;
                let c = if r < n && less(self.entries[r].0, self.entries[l].0) { r } else { l };
                if !less(self.entries[c].0, self.entries[i].0) {
                    return;
                }
                self.entries.swap(i, c);
                i = c;
            }
        }
    }

    /// Random pushes, updates (up and down), removals and pops with keys from a handful of
    /// values, so most comparisons are ties: the same nodes come out in the same order as from
    /// the textbook heap, with the same keys.
    #[test]
    fn same_pop_order_as_the_textbook_heap_under_ties() {
        for seed in 0..200u64 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let nodes = rng.random_range(1..60);
            let levels = rng.random_range(1..5);
            let key = |rng: &mut rand_chacha::ChaCha8Rng| {
                [rng.random_range(0..levels) as f64 * 0.5, rng.random_range(0..levels) as f64]
            };
            let (mut ours, mut textbook) = (IndexedHeap::new(nodes), Textbook::default());
            for step in 0..400 {
                match rng.random_range(0..10) {
                    0..=5 => {
                        let (n, k) = (rng.random_range(0..nodes), key(&mut rng));
                        ours.push_or_update(n, k);
                        textbook.push_or_update(n, k);
                    }
                    6 => {
                        let n = rng.random_range(0..nodes);
                        ours.remove(n);
                        if let Some(i) = textbook.find(n) {
                            textbook.remove_at(i);
                        }
                    }
                    _ => {
                        let expected = (!textbook.entries.is_empty()).then(|| {
                            let top = textbook.entries[0];
                            textbook.remove_at(0);
                            top
                        });
                        assert_eq!(ours.pop(), expected, "seed {seed} step {step}");
                    }
                }
                assert_eq!(ours.len(), textbook.entries.len());
                let top = textbook.entries.first().map_or([f64::INFINITY; 2], |e| e.0);
                assert_eq!(ours.top_key(), top);
            }
        }
    }
}
