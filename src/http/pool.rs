//! A bounded pool of OS threads for CPU work, with non-blocking admission.
//!
//! Why not `tokio::task::spawn_blocking`: its pool grows to 512 threads and its queue is
//! unbounded, so overload would show up as latency for everyone instead of a fast 429
//! for the excess. Here `workers` threads take jobs from a channel that holds at most
//! `queue` waiting jobs; `try_submit` never waits. A job owns its slot until it returns,
//! even when the request that submitted it has timed out or its client has gone, so the
//! pool's accounting always matches the CPU really in use.

use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use tokio::sync::oneshot;

type Job = Box<dyn FnOnce() + Send + 'static>;

/// The pool is full: every worker is busy and the queue holds `queue` jobs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PoolFull;

/// The job panicked; the payload's message if it had one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct JobPanicked(pub String);

/// What a finished job reports: its value, or its panic.
pub type JobResult<T> = Result<Started<T>, JobPanicked>;

/// A job's value with the time it waited in the queue.
#[derive(Debug)]
pub struct Started<T> {
    /// The job's return value.
    pub value: T,
    /// Milliseconds between submission and the start of the job.
    pub queued_ms: f64,
}

/// Counts shared with the metrics.
#[derive(Debug, Default)]
pub struct PoolCounts {
    /// Jobs submitted and not yet started.
    pub queued: AtomicUsize,
    /// Jobs running.
    pub running: AtomicUsize,
}

/// Tells a running job whether the pool has a worker with nothing to do (see
/// [`WorkerPool::spare_probe`]).
#[derive(Debug, Clone)]
pub struct SpareProbe {
    counts: Arc<PoolCounts>,
    workers: usize,
}

impl SpareProbe {
    /// True when fewer jobs are running (the asking one included) than there are
    /// workers and none is queued: a CPU the pool was sized for is free.
    pub fn has_spare_worker(&self) -> bool {
        self.counts.queued.load(Ordering::SeqCst) == 0
            && self.counts.running.load(Ordering::SeqCst) < self.workers
    }
}

/// The worker pool.
#[derive(Debug)]
pub struct WorkerPool {
    sender: SyncSender<Job>,
    counts: Arc<PoolCounts>,
    workers: usize,
    queue: usize,
}

impl WorkerPool {
    /// Starts `workers` threads (at least one) with room for `queue` waiting jobs.
    pub fn new(workers: usize, queue: usize) -> std::io::Result<Self> {
        let workers = workers.max(1);
        let (sender, receiver) = sync_channel::<Job>(queue);
        let receiver = Arc::new(Mutex::new(receiver));
        for i in 0..workers {
            let receiver = Arc::clone(&receiver);
            std::thread::Builder::new()
                .name(format!("ariadne-worker-{i}"))
                .spawn(move || worker_loop(&receiver))?;
        }
        Ok(Self {
            sender,
            counts: Arc::new(PoolCounts::default()),
            workers,
            queue,
        })
    }

    /// Number of worker threads.
    pub fn workers(&self) -> usize {
        self.workers
    }

    /// Capacity of the queue.
    pub fn queue_capacity(&self) -> usize {
        self.queue
    }

    /// Live counts of queued and running jobs.
    pub fn counts(&self) -> &PoolCounts {
        &self.counts
    }

    /// A handle a job can ask, while it runs, whether a worker would otherwise idle.
    pub fn spare_probe(&self) -> SpareProbe {
        SpareProbe {
            counts: Arc::clone(&self.counts),
            workers: self.workers,
        }
    }

    /// Blocks until no job is queued or running, or `timeout` has passed; true when idle.
    /// Shutdown calls it so that work still running for clients that have gone (which
    /// the HTTP drain does not wait for) ends before the process does.
    pub fn wait_idle(&self, timeout: Duration) -> bool {
        let until = Instant::now() + timeout;
        loop {
            let busy = self.counts.queued.load(Ordering::SeqCst)
                + self.counts.running.load(Ordering::SeqCst);
            if busy == 0 {
                return true;
            }
            if Instant::now() >= until {
                return false;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Queues `f` if there is room, else returns [`PoolFull`] at once. The receiver gets
    /// the job's value (or its panic) when it ends; dropping the receiver does not stop
    /// the job.
    pub fn try_submit<T, F>(&self, f: F) -> Result<oneshot::Receiver<JobResult<T>>, PoolFull>
    where
        T: Send + 'static,
        F: FnOnce() -> T + Send + 'static,
    {
        let (tx, rx) = oneshot::channel();
        let counts = Arc::clone(&self.counts);
        let submitted = Instant::now();
        let job: Job = Box::new(move || {
            counts.queued.fetch_sub(1, Ordering::SeqCst);
            counts.running.fetch_add(1, Ordering::SeqCst);
            let queued_ms = submitted.elapsed().as_secs_f64() * 1e3;
            let result = std::panic::catch_unwind(AssertUnwindSafe(f))
                .map(|value| Started { value, queued_ms })
                .map_err(|payload| {
                    let msg = payload
                        .downcast_ref::<&str>()
                        .map(|s| s.to_string())
                        .or_else(|| payload.downcast_ref::<String>().cloned())
                        .unwrap_or_else(|| "non-string panic payload".into());
                    JobPanicked(msg)
                });
            counts.running.fetch_sub(1, Ordering::SeqCst);
            // The requester may have gone (timeout, disconnect): nothing to tell then.
            let _ = tx.send(result);
        });
        self.counts.queued.fetch_add(1, Ordering::SeqCst);
        match self.sender.try_send(job) {
            Ok(()) => Ok(rx),
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => {
                self.counts.queued.fetch_sub(1, Ordering::SeqCst);
                Err(PoolFull)
            }
        }
    }
}

fn worker_loop(receiver: &Mutex<Receiver<Job>>) {
    loop {
        // Hold the lock only to take one job, not while running it.
        let job = match receiver.lock() {
            Ok(guard) => guard.recv(),
            Err(poisoned) => poisoned.into_inner().recv(),
        };
        match job {
            Ok(job) => job(),
            Err(_) => return, // the pool was dropped
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn waits_for_jobs_whose_requester_has_gone() {
        let pool = WorkerPool::new(1, 2).unwrap();
        assert!(pool.wait_idle(Duration::ZERO));
        let (done_tx, done_rx) = std::sync::mpsc::channel();
        // Submitted, then forgotten: the receiver is dropped at once.
        drop(pool.try_submit(move || {
            std::thread::sleep(Duration::from_millis(50));
            done_tx.send(()).unwrap();
        }));
        assert!(!pool.wait_idle(Duration::from_millis(1)));
        assert!(pool.wait_idle(Duration::from_secs(5)));
        assert!(done_rx.try_recv().is_ok(), "the job ran to its end");
    }

    #[tokio::test]
    async fn runs_jobs_rejects_overflow_and_survives_panics() {
        let pool = WorkerPool::new(1, 1).unwrap();
        let (release_tx, release_rx) = std::sync::mpsc::channel::<()>();
        let blocker = pool.try_submit(move || release_rx.recv().is_ok()).unwrap();
        // Wait until the worker has taken the blocker, so the queue is empty again.
        while pool.counts().running.load(Ordering::SeqCst) == 0 {
            tokio::time::sleep(Duration::from_millis(1)).await;
        }
        let queued = pool.try_submit(|| 7).unwrap();
        assert_eq!(pool.try_submit(|| 8).unwrap_err(), PoolFull);
        release_tx.send(()).unwrap();
        assert!(blocker.await.unwrap().unwrap().value);
        assert_eq!(queued.await.unwrap().unwrap().value, 7);
        let panicked = pool.try_submit(|| -> u8 { panic!("boom") }).unwrap();
        assert_eq!(
            panicked.await.unwrap().unwrap_err(),
            JobPanicked("boom".into())
        );
        assert_eq!(
            pool.try_submit(|| 9).unwrap().await.unwrap().unwrap().value,
            9
        );
    }

    /// A job alone in a two-worker pool has a spare worker beside it; the second of two
    /// running jobs has none.
    #[test]
    fn a_job_learns_whether_a_worker_is_spare() {
        let pool = WorkerPool::new(2, 4).unwrap();
        let (seen_tx, seen_rx) = std::sync::mpsc::channel();
        let mut releases = Vec::new();
        for _ in 0..2 {
            let (release_tx, release_rx) = std::sync::mpsc::channel::<()>();
            let (probe, seen_tx) = (pool.spare_probe(), seen_tx.clone());
            drop(pool.try_submit(move || {
                seen_tx.send(probe.has_spare_worker()).unwrap();
                release_rx.recv().unwrap();
            }));
            // Each job has started (and holds its worker) before the next is submitted.
            let seen = seen_rx.recv_timeout(Duration::from_secs(10)).unwrap();
            releases.push((seen, release_tx));
        }
        let seen: Vec<bool> = releases.iter().map(|(seen, _)| *seen).collect();
        assert_eq!(seen, [true, false]);
        for (_, release) in releases {
            release.send(()).unwrap();
        }
        assert!(pool.wait_idle(Duration::from_secs(10)));
    }
}
