//! Running work without the interpreter's lock while keeping Ctrl-C working: the work runs on
//! a scoped thread; the calling thread waits without the lock and, every
//! [`SIGNAL_CHECK_INTERVAL`], takes it to run Python's signal handlers. When one raises (e.g.
//! `KeyboardInterrupt`), the stop flag is set, the work finishes its current iteration and
//! returns, and the exception is raised then.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use pyo3::prelude::*;

/// How often the waiting thread checks for signals.
const SIGNAL_CHECK_INTERVAL: Duration = Duration::from_millis(50);

/// Runs `work` (given the stop flag) off the interpreter's lock; returns its result, or the
/// exception a signal handler raised while it ran (after the work has stopped).
pub fn run_interruptible<T: Send>(py: Python<'_>, work: impl FnOnce(&AtomicBool) -> T + Send) -> PyResult<T> {
    let stop = AtomicBool::new(false);
    let (sender, mut receiver) = mpsc::channel();
    std::thread::scope(|scope| {
        let stop = &stop;
        scope.spawn(move || {
            // The receiver is gone only if the waiting thread panicked; nothing to tell then.
            let _ = sender.send(work(stop));
        });
        let mut raised = None;
        loop {
            let (back, received) = py.detach(move || {
                let received = receiver.recv_timeout(SIGNAL_CHECK_INTERVAL);
                (receiver, received)
            });
            receiver = back;
            match received {
                Ok(value) => return raised.map_or(Ok(value), Err),
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if raised.is_none()
                        && let Err(error) = py.check_signals()
                    {
                        stop.store(true, Ordering::SeqCst);
                        raised = Some(error);
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(pyo3::exceptions::PyRuntimeError::new_err("the render thread panicked"));
                }
            }
        }
    })
}
