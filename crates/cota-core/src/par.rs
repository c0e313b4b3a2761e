//! Entering the rayon pool once per public entry point.
//!
//! A parallel section entered from outside the pool hands its work to the
//! pool and waits to be woken; one entered from a worker costs well under a
//! microsecond. So each public entry point that runs several parallel
//! sections (the build, the extraction, the metrics) enters the pool once,
//! through [`on_pool`].

/// Runs `f` on a rayon worker thread. A parallel section entered from outside
/// the pool hands its work to the pool and waits to be woken (about 30 µs per
/// section on the 2-core benchmark machine); one entered from a worker costs
/// well under a microsecond. So each public entry point that runs several
/// parallel sections enters the pool once, here.
pub(crate) fn on_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    if rayon::current_thread_index().is_some() {
        f()
    } else {
        rayon::scope(|_| f())
    }
}
