//! A least-recently-used map bounded in bytes: the tiles the server keeps.

use std::collections::{BTreeMap, HashMap};
use std::hash::Hash;

/// Values with their sizes; past `cap` bytes the least recently used go.
#[derive(Debug)]
pub(crate) struct ByteLru<K, V> {
    map: HashMap<K, (V, usize, u64)>,
    order: BTreeMap<u64, K>,
    bytes: usize,
    cap: usize,
    tick: u64,
}

impl<K: Hash + Eq + Copy, V: Clone> ByteLru<K, V> {
    /// An empty cache of at most `cap` bytes.
    pub(crate) fn new(cap: usize) -> Self {
        ByteLru {
            map: HashMap::new(),
            order: BTreeMap::new(),
            bytes: 0,
            cap,
            tick: 0,
        }
    }

    /// The value of `k`, now the most recently used.
    pub(crate) fn get(&mut self, k: &K) -> Option<V> {
        self.tick += 1;
        let (v, _, t) = self.map.get_mut(k)?;
        self.order.remove(t);
        *t = self.tick;
        self.order.insert(self.tick, *k);
        Some(v.clone())
    }

    /// Keeps `v` of `size` bytes under `k` (not kept when larger than the
    /// cache), dropping the least recently used beyond the cap.
    pub(crate) fn insert(&mut self, k: K, v: V, size: usize) {
        if size > self.cap {
            return;
        }
        self.remove(&k);
        self.tick += 1;
        self.map.insert(k, (v, size, self.tick));
        self.order.insert(self.tick, k);
        self.bytes += size;
        while self.bytes > self.cap {
            let Some((_, old)) = self.order.pop_first() else {
                break;
            };
            if let Some((_, n, _)) = self.map.remove(&old) {
                self.bytes -= n;
            }
        }
    }

    fn remove(&mut self, k: &K) {
        if let Some((_, n, t)) = self.map.remove(k) {
            self.order.remove(&t);
            self.bytes -= n;
        }
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        self.bytes
    }

    /// Entries held.
    pub(crate) fn len(&self) -> usize {
        self.map.len()
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn least_recently_used_go_first_and_bytes_stay_bounded() {
        let mut c = ByteLru::new(10);
        c.insert(1, 'a', 4);
        c.insert(2, 'b', 4);
        assert_eq!(c.get(&1), Some('a'));
        c.insert(3, 'c', 4);
        assert_eq!(c.get(&2), None, "2 was the least recently used");
        assert_eq!((c.get(&1), c.get(&3)), (Some('a'), Some('c')));
        assert_eq!((c.bytes(), c.len()), (8, 2));
        c.insert(4, 'd', 11);
        assert_eq!(c.get(&4), None, "larger than the cache");
        c.insert(1, 'e', 2);
        assert_eq!((c.get(&1), c.bytes()), (Some('e'), 6));
        for k in 10..1000 {
            c.insert(k, 'x', 3);
            assert!(c.bytes() <= 10);
        }
    }
}
