//! A fixed pool of worker threads fed by a bounded queue: the only place
//! where tiles are made or read, so that a burst of requests costs at most
//! `workers` threads and `queue` waiting jobs, never more.

use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender, TrySendError};
use std::sync::{Arc, Mutex};

use tokio::sync::oneshot;

type Job = Box<dyn FnOnce() + Send + 'static>;

/// The queue is full: the job was not taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Busy;

/// Worker threads and their queue.
#[derive(Debug)]
pub(crate) struct Pool {
    tx: Mutex<SyncSender<Job>>,
    busy: Arc<AtomicUsize>,
    workers: usize,
}

impl Pool {
    /// Starts `workers` threads (at least 1) behind a queue of `queue` jobs.
    pub(crate) fn new(workers: usize, queue: usize) -> Self {
        let (tx, rx) = sync_channel::<Job>(queue);
        let rx = Arc::new(Mutex::new(rx));
        let busy = Arc::new(AtomicUsize::new(0));
        let workers = workers.max(1);
        for k in 0..workers {
            let (rx, busy) = (rx.clone(), busy.clone());
            // Without the thread the pool has fewer workers; jobs still run.
            let _ = std::thread::Builder::new()
                .name(format!("cota-tiles-{k}"))
                .spawn(move || work(&rx, &busy));
        }
        Pool {
            tx: Mutex::new(tx),
            busy,
            workers,
        }
    }

    /// Queues `f`; its result arrives on the receiver (closed without a
    /// value if `f` panicked).
    ///
    /// # Errors
    /// [`Busy`] when the queue is full.
    pub(crate) fn try_run<T: Send + 'static>(
        &self,
        f: impl FnOnce() -> T + Send + 'static,
    ) -> Result<oneshot::Receiver<T>, Busy> {
        let (done, rx) = oneshot::channel();
        let job: Job = Box::new(move || {
            // The requester may be gone; the result is then dropped.
            let _ = done.send(f());
        });
        let tx = self.tx.lock().unwrap_or_else(|p| p.into_inner());
        match tx.try_send(job) {
            Ok(()) => Ok(rx),
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => Err(Busy),
        }
    }

    /// Workers running a job now.
    pub(crate) fn busy(&self) -> usize {
        self.busy.load(Ordering::Relaxed)
    }

    /// Worker threads.
    pub(crate) fn workers(&self) -> usize {
        self.workers
    }
}

fn work(rx: &Mutex<Receiver<Job>>, busy: &AtomicUsize) {
    loop {
        let job = {
            let rx = rx.lock().unwrap_or_else(|p| p.into_inner());
            match rx.recv() {
                Ok(job) => job,
                Err(_) => return,
            }
        };
        busy.fetch_add(1, Ordering::Relaxed);
        // A panicking job drops its sender (the request gets 500); the
        // worker lives on.
        let _ = std::panic::catch_unwind(AssertUnwindSafe(job));
        busy.fetch_sub(1, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use std::sync::Barrier;

    #[test]
    fn a_full_queue_refuses_and_work_goes_on() {
        let pool = Pool::new(1, 1);
        let gate = Arc::new(Barrier::new(2));
        let g = gate.clone();
        let first = pool.try_run(move || {
            g.wait();
            1
        });
        assert!(first.is_ok());
        // The worker holds the first job; wait until it has taken it.
        while pool.busy() == 0 {
            std::thread::yield_now();
        }
        let second = pool.try_run(|| 2).expect("one job waits");
        assert_eq!(pool.try_run(|| 3).unwrap_err(), Busy);
        gate.wait();
        assert_eq!(first.unwrap().blocking_recv().ok(), Some(1));
        assert_eq!(second.blocking_recv().ok(), Some(2));
        let panics = pool.try_run(|| -> u8 { panic!("job") }).unwrap();
        assert!(panics.blocking_recv().is_err());
        assert_eq!(pool.try_run(|| 4).unwrap().blocking_recv().ok(), Some(4));
    }
}
