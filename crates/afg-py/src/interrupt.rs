//! Long work off the interpreter's lock that still answers Ctrl-C.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, PoisonError, mpsc};
use std::time::Duration;

use pyo3::prelude::*;

/// Runs `work` on another thread, the interpreter's lock released, while this one
/// answers signals: Ctrl-C sets `stop` (the exact search ends at its next step with
/// the best found; other work runs to its end) and `KeyboardInterrupt` is raised once
/// `work` has returned. Work that ends first returns at once.
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    stop: &AtomicBool,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    let (done, finished) = mpsc::sync_channel(1);
    let finished = Mutex::new(finished); // shared with the thread that waits on it
    std::thread::scope(|scope| {
        scope.spawn(move || {
            // the receiver waits on this scope, so it is there to take the result
            let _ = done.send(work());
        });
        let mut interrupted = None;
        loop {
            match py.detach(|| {
                let finished = finished.lock().unwrap_or_else(PoisonError::into_inner);
                finished.recv_timeout(Duration::from_millis(50))
            }) {
                Ok(out) => return interrupted.map_or(Ok(out), Err),
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(pyo3::exceptions::PyRuntimeError::new_err(
                        "afg: the solve panicked (a bug: please report it)",
                    ));
                }
            }
            if interrupted.is_none()
                && let Err(signal) = py.check_signals()
            {
                stop.store(true, Ordering::Relaxed);
                interrupted = Some(signal);
            }
        }
    })
}
