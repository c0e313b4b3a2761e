//! Where tiles are made: the bounded [`Pool`], the byte-bounded tile cache
//! and one shared making per tile. A request for a tile in the cache is
//! answered at once; one being made waits for that making; any other is
//! queued on the pool, or refused with 503 when the queue is full.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use tokio::sync::watch;

use crate::cache::ByteLru;
use crate::error::{Result, ServeError};
use crate::options::ServeOptions;
use crate::pool::Pool;
use crate::tiles::{Tile, TileId};

/// What is made: a terrain tile or an imagery tile.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Key {
    /// `/tiles/{z}/{x}/{y}.terrain`.
    Terrain(TileId),
    /// `/imagery/{z}/{x}/{y}.png`.
    Imagery(TileId),
}

/// The outcome of one making, shared by every request that waited for it.
type Outcome = Option<std::result::Result<Tile, Arc<ServeError>>>;

/// Counters for `/health` and the load benchmarks.
#[derive(Debug, Default)]
pub(crate) struct Counters {
    /// Tiles made (or read) by the pool.
    pub(crate) made: AtomicU64,
    /// Requests answered from the cache.
    pub(crate) hits: AtomicU64,
    /// Requests that waited for a making another request started.
    pub(crate) shared: AtomicU64,
    /// Requests refused with 503 (queue full).
    pub(crate) refused: AtomicU64,
}

/// The pool, the cache and the makings in flight.
#[derive(Debug)]
pub(crate) struct Work {
    pool: Pool,
    cache: Mutex<ByteLru<Key, Tile>>,
    inflight: Mutex<HashMap<Key, watch::Receiver<Outcome>>>,
    retry_after_s: u64,
    pub(crate) counters: Counters,
}

impl Work {
    pub(crate) fn new(o: &ServeOptions) -> Self {
        Work {
            pool: Pool::new(o.workers, o.queue),
            cache: Mutex::new(ByteLru::new(o.cache_bytes)),
            inflight: Mutex::new(HashMap::new()),
            retry_after_s: o.retry_after_s,
            counters: Counters::default(),
        }
    }

    /// The tile `key`: from the cache, from a making in flight, or made by
    /// `make` on the pool (and kept).
    ///
    /// # Errors
    /// [`ServeError::Unavailable`] when the queue is full; what `make`
    /// returned; [`ServeError::Internal`] when it panicked.
    pub(crate) async fn get(
        self: &Arc<Self>,
        key: Key,
        make: impl FnOnce() -> Result<Tile> + Send + 'static,
    ) -> Result<Tile> {
        if let Some(t) = self.lock_cache().get(&key) {
            self.counters.hits.fetch_add(1, Ordering::Relaxed);
            return Ok(t);
        }
        let mut rx = {
            let mut inflight = self.inflight.lock().unwrap_or_else(|p| p.into_inner());
            if let Some(t) = self.lock_cache().get(&key) {
                // Made between the first look and this one.
                return Ok(t);
            }
            match inflight.get(&key) {
                Some(rx) => {
                    self.counters.shared.fetch_add(1, Ordering::Relaxed);
                    rx.clone()
                }
                None => {
                    let (tx, rx) = watch::channel(None);
                    self.start(key, tx, make)?;
                    inflight.insert(key, rx.clone());
                    rx
                }
            }
        };
        let outcome = rx
            .wait_for(Option::is_some)
            .await
            .map_err(|_| ServeError::Internal("tile making ended without a result".into()))?;
        match outcome.as_ref() {
            Some(Ok(t)) => Ok(t.clone()),
            Some(Err(e)) => Err(ServeError::Shared(e.clone())),
            None => Err(ServeError::Internal("no tile".into())),
        }
    }

    /// Queues the making of `key`; its outcome is kept and sent to the
    /// waiters by a task of its own, so it lands even if every requester
    /// has gone.
    fn start(
        self: &Arc<Self>,
        key: Key,
        tx: watch::Sender<Outcome>,
        make: impl FnOnce() -> Result<Tile> + Send + 'static,
    ) -> Result<()> {
        let Ok(done) = self.pool.try_run(make) else {
            self.counters.refused.fetch_add(1, Ordering::Relaxed);
            return Err(self.busy());
        };
        let work = self.clone();
        tokio::spawn(async move {
            let outcome = match done.await {
                Ok(Ok(t)) => {
                    work.counters.made.fetch_add(1, Ordering::Relaxed);
                    let size = t.bytes.len() + 128;
                    work.lock_cache().insert(key, t.clone(), size);
                    Ok(t)
                }
                Ok(Err(e)) => Err(Arc::new(e)),
                Err(_) => Err(Arc::new(ServeError::Internal(
                    "the tile maker panicked".into(),
                ))),
            };
            let mut inflight = work.inflight.lock().unwrap_or_else(|p| p.into_inner());
            inflight.remove(&key);
            // No receiver left: nobody waits; the tile is kept anyway.
            let _ = tx.send(Some(outcome));
        });
        Ok(())
    }

    /// The 503 of a full queue.
    pub(crate) fn busy(&self) -> ServeError {
        ServeError::Unavailable {
            reason: "every tile worker is busy and the queue is full".into(),
            retry_after_s: self.retry_after_s,
        }
    }

    fn lock_cache(&self) -> std::sync::MutexGuard<'_, ByteLru<Key, Tile>> {
        self.cache.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// A JSON summary for `/health`.
    pub(crate) fn summary(&self) -> serde_json::Value {
        let c = &self.counters;
        let cache = self.lock_cache();
        serde_json::json!({
            "workers": self.pool.workers(),
            "busy": self.pool.busy(),
            "made": c.made.load(Ordering::Relaxed),
            "cache_hits": c.hits.load(Ordering::Relaxed),
            "shared": c.shared.load(Ordering::Relaxed),
            "refused": c.refused.load(Ordering::Relaxed),
            "cache_tiles": cache.len(),
            "cache_bytes": cache.bytes(),
        })
    }
}
