//! [`ServeOptions`]: the bounds a server keeps under load (work, memory,
//! connections, time), each with its default.

use std::time::Duration;

/// How much work, memory, connections and time the server gives its
/// clients. Past a bound it answers `503 Service Unavailable` with
/// `Retry-After` rather than queueing without limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub struct ServeOptions {
    /// Threads that make tiles (terrain cut on demand, imagery, tile files
    /// read from disk). Default: the machine's cores, at most 8 (see
    /// [`ServeOptions::default_workers`]).
    pub workers: usize,
    /// Tiles that may wait for a worker; a request past them gets 503.
    /// Default: 64.
    pub queue: usize,
    /// Bytes of tiles (terrain and imagery, as sent) kept in memory, least
    /// recently used first out. Default: 256 MiB.
    pub cache_bytes: usize,
    /// Connections open at once; one more is answered 503 and closed.
    /// Default: 512.
    pub max_connections: usize,
    /// Time a client has to send a request's headers (also the idle time of
    /// a kept-alive connection), seconds. Default: 10.
    pub header_timeout_s: u64,
    /// Time the server takes at most to answer one request, seconds; past
    /// it the answer is 503. Default: 30.
    pub request_timeout_s: u64,
    /// Seconds a 503 asks the client to wait (`Retry-After`). Default: 1.
    pub retry_after_s: u64,
    /// Tokio threads that run the connections. Default: the machine's
    /// cores, at most 4.
    pub io_threads: usize,
}

impl ServeOptions {
    /// The defaults, with [`ServeOptions::default_workers`] workers.
    pub fn new() -> Self {
        ServeOptions {
            workers: Self::default_workers(),
            queue: 64,
            cache_bytes: 256 << 20,
            max_connections: 512,
            header_timeout_s: 10,
            request_timeout_s: 30,
            retry_after_s: 1,
            io_threads: cores().min(4),
        }
    }

    /// The machine's cores, at most 8: tile cutting is CPU-bound, so more
    /// threads than cores only add memory.
    pub fn default_workers() -> usize {
        cores().min(8)
    }

    /// Sets [`ServeOptions::workers`] (at least 1).
    pub fn with_workers(mut self, n: usize) -> Self {
        self.workers = n.max(1);
        self
    }

    /// Sets [`ServeOptions::queue`].
    pub fn with_queue(mut self, n: usize) -> Self {
        self.queue = n;
        self
    }

    /// Sets [`ServeOptions::cache_bytes`].
    pub fn with_cache_bytes(mut self, n: usize) -> Self {
        self.cache_bytes = n;
        self
    }

    /// Sets [`ServeOptions::max_connections`] (at least 1).
    pub fn with_max_connections(mut self, n: usize) -> Self {
        self.max_connections = n.max(1);
        self
    }

    /// Sets [`ServeOptions::header_timeout_s`] (at least 1).
    pub fn with_header_timeout_s(mut self, s: u64) -> Self {
        self.header_timeout_s = s.max(1);
        self
    }

    /// Sets [`ServeOptions::request_timeout_s`] (at least 1).
    pub fn with_request_timeout_s(mut self, s: u64) -> Self {
        self.request_timeout_s = s.max(1);
        self
    }

    /// Sets [`ServeOptions::io_threads`] (at least 1).
    pub fn with_io_threads(mut self, n: usize) -> Self {
        self.io_threads = n.max(1);
        self
    }

    pub(crate) fn header_timeout(&self) -> Duration {
        Duration::from_secs(self.header_timeout_s)
    }

    pub(crate) fn request_timeout(&self) -> Duration {
        Duration::from_secs(self.request_timeout_s)
    }
}

impl Default for ServeOptions {
    fn default() -> Self {
        Self::new()
    }
}

fn cores() -> usize {
    std::thread::available_parallelism().map_or(2, |n| n.get())
}
