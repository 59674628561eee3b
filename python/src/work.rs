//! Long calls off the GIL: interruptible by Ctrl-C, cancellable between steps, on a sized thread pool.

use crate::errors::*;
use pyo3::prelude::*;

/// Runs `work` on its own thread with the GIL released, checking for Ctrl-C (and any other
/// pending Python signal) every 50 ms: an interrupt raises `KeyboardInterrupt` at once, the
/// abandoned work finishing in the background with its result dropped. For work that writes
/// files, use [`cancellable`].
pub(crate) fn interruptible<T: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce() -> T + Send + 'static,
) -> PyResult<T> {
    cancellable(py, move |_| work())
}

/// A flag set when the call that started a work was interrupted: the work asks it between its
/// steps and before each write, and stops (nothing written after the exception was raised,
/// beyond a file whose writing had already begun).
pub(crate) type Cancel = std::sync::Arc<std::sync::atomic::AtomicBool>;

/// Whether `cancel` is set.
pub(crate) fn is_cancelled(cancel: &Cancel) -> bool {
    cancel.load(std::sync::atomic::Ordering::SeqCst)
}

/// [`interruptible`], the work handed the flag an interrupt sets ([`Cancel`]).
pub(crate) fn cancellable<T: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce(Cancel) -> T + Send + 'static,
) -> PyResult<T> {
    reporting(
        py,
        move |cancel, _: Progress<()>| work(cancel),
        |_, ()| Ok(()),
    )
}

/// Where a work sends its progress (a fraction done, a cell finished), from any of its
/// threads, for the calling thread.
pub(crate) type Progress<P> = std::sync::mpsc::Sender<P>;

/// [`cancellable`], the work also handed a [`Progress`] channel: what it sends is handed to
/// `on_progress` on the calling thread, with the GIL, in the order it was sent, within 50 ms,
/// and all of it before the result returns. An exception in `on_progress` cancels the work
/// and is raised at once.
pub(crate) fn reporting<T: Send + 'static, P: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce(Cancel, Progress<P>) -> T + Send + 'static,
    mut on_progress: impl FnMut(Python<'_>, P) -> PyResult<()>,
) -> PyResult<T> {
    let cancel: Cancel = Default::default();
    let flag = cancel.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    let (progress, reports) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("physid".into())
        .spawn(move || {
            let _ = tx.send(work(flag, progress));
        })
        .map_err(|e| exception(format!("could not start a worker thread: {e}")))?;
    let stop = |e: PyErr| {
        cancel.store(true, std::sync::atomic::Ordering::SeqCst);
        Err(e)
    };
    let mut rx = rx;
    loop {
        let tick = std::time::Duration::from_millis(50);
        let (got, back) = py.allow_threads(move || (rx.recv_timeout(tick), rx));
        rx = back;
        // Every report sent before the result is in the channel by now.
        while let Ok(p) = reports.try_recv() {
            if let Err(e) = on_progress(py, p) {
                return stop(e);
            }
        }
        match got {
            Ok(out) => return Ok(out),
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                if let Err(interrupt) = py.check_signals() {
                    return stop(interrupt);
                }
            }
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                return Err(pyo3::exceptions::PyRuntimeError::new_err(
                    "physid's worker thread panicked: please report this with its input",
                ))
            }
        }
    }
}

/// A worker pool of `threads` threads (none or 0: all cores), never more than the machine's
/// cores. Results do not depend on it.
pub(crate) fn thread_pool(threads: Option<usize>) -> PyResult<rayon::ThreadPool> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let workers = threads.filter(|&t| t > 0).unwrap_or(cores).min(cores);
    rayon::ThreadPoolBuilder::new()
        .num_threads(workers)
        .thread_name(|i| format!("physid-rayon-{i}"))
        .build()
        .map_err(exception)
}
