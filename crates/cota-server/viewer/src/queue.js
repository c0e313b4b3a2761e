// The refinement's schedule (lod.js): candidates keyed by the eye's travel in
// metres at which their decision can next change; each frame takes out those
// whose key the travel has reached.
//
// The keys taken out never decrease and every key put in is at least the
// travel so far, so the schedule is a radix heap (Ahuja, Mehlhorn, Orlin and
// Tarjan, "Faster algorithms for the shortest path problem", 1990): an entry
// goes into the bucket of the highest bit in which its key, in 1/16 m, differs
// from the travel at the last frame, and the buckets hold increasing ranges
// of keys. A frame does not take entries out one by one in key order: the
// buckets the travel has reached join the due list whole (no copy), and the
// entries found there beyond the travel go back into lower buckets as they
// are met, under the frame's time budget (when the travel crosses a high bit,
// one bucket can hold most of the schedule). Pushing is an append, and an
// entry moves about log2(its slack / a frame's travel) times, each a
// sequential copy, where a binary heap of 300,000 candidates costs about 18
// random accesses a pop. The due list is first in, first out: the most overdue
// first (the buckets join it in key order), then what this frame's decisions
// scheduled.
//
// Deletion is lazy: each node has a version, an entry is live while it carries
// its node's current version, and pushing or removing a node bumps it (so a
// node has one live entry at most, and rescheduling is a push). Each entry also
// carries what its decision needs (the centre height and radius of its
// diamond's sphere, the distance at which its screen error is the target), so
// deciding again a candidate whose state has not changed reads the entry alone.

/** Keys are put in buckets in 1/16 m (the keys themselves are exact). */
const Q = 16;
const BUCKETS = 55;
/** Doubles an entry: key, node, version, kind, centre z, radius, target distance. */
const STRIDE = 7;

/** Index of the highest bit in which a ≥ b differ, plus one (0 when equal); a, b < 2^53. */
function bucketOf(a, b) {
  const ha = Math.floor(a / 4294967296), hb = Math.floor(b / 4294967296);
  if (ha !== hb) return 64 - Math.clz32(ha ^ hb);
  return 32 - Math.clz32((a >>> 0) ^ (b >>> 0));
}

/**
 * Storage to reuse, by size: spare[c] holds free arrays of 2^c entries (a
 * few of each; the rest are left to the garbage collector).
 */
const SPARE_EACH = 4;

/** A free array of at least `n` entries from `spare` (2^c of them), or a new one. */
function take(spare, n) {
  const c = Math.max(6, 32 - Math.clz32(n - 1));
  for (let k = c; k < Math.min(c + 3, spare.length); k++) {
    if (spare[k].length > 0) return spare[k].pop();
  }
  return new Float64Array(STRIDE << c);
}

/** Gives array `d` back to `spare`. */
function give(spare, d) {
  const c = 31 - Math.clz32(d.length / STRIDE);
  while (spare.length <= c) spare.push([]);
  if (spare[c].length < SPARE_EACH) spare[c].push(d);
}

/** A growable array of entries; storage comes from and goes back to `spare`. */
class Entries {
  constructor(spare, cap) {
    this.spare = spare;
    this.d = take(spare, cap);
    this.head = 0;
    this.size = 0;
  }

  /** Makes room for one more at the end (dropping the taken-out front first). */
  room() {
    if (this.head > this.size >> 1) {
      this.d.copyWithin(0, this.head * STRIDE, this.size * STRIDE);
      this.size -= this.head;
      this.head = 0;
      return;
    }
    const g = take(this.spare, (2 * this.d.length) / STRIDE);
    g.set(this.d.subarray(0, this.size * STRIDE));
    give(this.spare, this.d);
    this.d = g;
  }

  /** Gives its storage back (it is not used again). */
  release() {
    give(this.spare, this.d);
    this.d = null;
  }

  add(key, node, v, kind, cz, r, dT) {
    if ((this.size + 1) * STRIDE > this.d.length) this.room();
    const d = this.d, o = this.size++ * STRIDE;
    d[o] = key;
    d[o + 1] = node;
    d[o + 2] = v;
    d[o + 3] = kind;
    d[o + 4] = cz;
    d[o + 5] = r;
    d[o + 6] = dT;
  }

  /** Keeps only the live entries. Returns how many. */
  filter(ver) {
    const d = this.d;
    let w = 0;
    for (let o = this.head * STRIDE; o < this.size * STRIDE; o += STRIDE) {
      if (ver[d[o + 1]] !== d[o + 2]) continue;
      if (w !== o) d.copyWithin(w, o, o + STRIDE);
      w += STRIDE;
    }
    this.head = 0;
    this.size = w / STRIDE;
    return this.size;
  }
}

export class SlackQueue {
  /** @param {number} nodes how many node indices there are */
  constructor(nodes) {
    this.ver = new Int32Array(nodes);
    /** Storage to reuse. */
    this.spare = [];
    this.buckets = [];
    for (let b = 0; b < BUCKETS; b++) this.buckets.push(new Entries(this.spare, 64));
    /**
     * The due list, first in first out, as a list of entry arrays taken out of
     * the buckets whole; its last is bucket 0 (keys up to lastQ, the travel at
     * the last frame in 1/16 m), where what a frame schedules for now goes.
     */
    this.chunks = [this.buckets[0]];
    this.ci = 0;
    /** Due entries found just beyond the travel (within its 1/16 m), for the next frame. */
    this.wait = new Entries(this.spare, 64);
    this.lastQ = 0;
    this.entries = 0;
    this.compactAt = 1 << 18;
    // The entry taken out by `popDue`.
    this.node = -1;
    this.kind = 0;
    this.cz = 0;
    this.r = 0;
    this.dT = 0;
  }

  /**
   * Schedules `node` at `key` (metres of travel; one behind the travel so far
   * is due at once), replacing its live entry: kind 0 for a full evaluation, else the kind
   * and the decision's constants.
   */
  push(node, key, kind, cz, r, dT) {
    const v = (this.ver[node] = (this.ver[node] + 1) | 0);
    // A key behind the last frame's travel is due now: bucket 0.
    const kq = Math.max(Math.floor(key * Q), this.lastQ);
    this.buckets[bucketOf(kq, this.lastQ)].add(key, node, v, kind, cz, r, dT);
    if (++this.entries > this.compactAt) this.compact();
  }

  /** Drops `node`'s live entry, if any. */
  remove(node) {
    this.ver[node] = (this.ver[node] + 1) | 0;
  }

  /** An empty entry array for about `n` entries (a bucket refills to about what it held). */
  fresh(n) {
    return new Entries(this.spare, Math.max(64, n + 1));
  }

  /**
   * Starts a frame at `travel`: the buckets it has reached join the due list
   * whole, the one it falls in too (its entries not due yet go back into
   * lower buckets as `popDue` meets them, within the frame's budget: a bucket
   * can hold most of the schedule when the travel crosses a high bit).
   */
  begin(travel) {
    const chunks = this.chunks;
    if (this.wait.size > 0) {
      // Before bucket 0 (the keys just beyond the last travel come first).
      chunks.splice(chunks.length - 1, 0, this.wait);
      this.wait = this.fresh(64);
    }
    const tq = Math.floor(travel * Q);
    const last = this.lastQ;
    if (tq <= last) return;
    let moved = false;
    for (let b = 1; b < BUCKETS; b++) {
      const e = this.buckets[b];
      if (e.size === 0) continue;
      // Bucket b holds the keys that share last's bits above b − 1 and have that bit set.
      const p = 2 ** (b - 1);
      if (Math.floor(last / (2 * p)) * 2 * p + p > tq) break;
      this.buckets[b] = this.fresh(e.size);
      if (!moved) {
        // Bucket 0 closes: the newly due keys follow it.
        moved = true;
        this.buckets[0] = this.fresh(this.buckets[0].size);
      }
      chunks.push(e);
    }
    if (moved) chunks.push(this.buckets[0]);
    this.lastQ = tq;
  }

  /**
   * Takes out the next live due entry of key ≤ `travel` into this.node,
   * kind, cz, r, dT: returns 1, or 0 when none is left, or 2 after looking
   * at `limit` entries without finding one (time to look at the clock).
   */
  popDue(travel, limit) {
    const ver = this.ver, chunks = this.chunks;
    for (;;) {
      const c = chunks[this.ci];
      const d = c.d;
      while (c.head < c.size) {
        const o = c.head++ * STRIDE;
        const key = d[o];
        if (key > travel) {
          const kq = Math.floor(key * Q);
          // Beyond this frame: within the travel's 1/16 m, wait for the next
          // frame; else back into its bucket (stale or not: its version is a
          // random access, looked up only when it is due).
          const to = kq <= this.lastQ ? this.wait : this.buckets[bucketOf(kq, this.lastQ)];
          to.add(key, d[o + 1], d[o + 2], d[o + 3], d[o + 4], d[o + 5], d[o + 6]);
          if (--limit === 0) return 2;
          continue;
        }
        const node = d[o + 1];
        if (ver[node] !== d[o + 2]) {
          this.entries--;
          if (--limit === 0) return 2;
          continue;
        }
        this.node = node;
        this.kind = d[o + 3];
        this.cz = d[o + 4];
        this.r = d[o + 5];
        this.dT = d[o + 6];
        this.entries--;
        return 1;
      }
      c.head = c.size = 0;
      if (this.ci === chunks.length - 1) {
        // Bucket 0, the last: emptied in place, everything due is done.
        if (this.ci > 0) {
          chunks.length = 0;
          chunks.push(c);
          this.ci = 0;
        }
        return 0;
      }
      c.release();
      this.ci++;
    }
  }

  /** Drops every stale entry (when there are four times as many as were live at the last compaction). */
  compact() {
    let live = this.wait.filter(this.ver);
    for (const e of this.buckets) live += e.filter(this.ver);
    for (let c = this.ci; c < this.chunks.length - 1; c++) live += this.chunks[c].filter(this.ver);
    this.entries = live;
    this.compactAt = 4 * live + (1 << 18);
  }
}
