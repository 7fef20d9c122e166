//! The scheduling priority of the tracer's threads: below the window's, so the UI stays responsive while the
//! tracer keeps every core busy, but not so far below that the tracer leaves a core idle.
//!
//! On Linux the tracer runs [`NICE_BELOW_UI`] niceness steps below the UI rather than at the lowest priority
//! (19). At 19 (a scheduler weight of 15 against the 1024 of the UI's and lavapipe's threads), a tracer
//! thread that lavapipe preempts in the middle of a tile waits on that core until lavapipe's draw is done; the
//! frame cannot end before that tile, so the other tracer thread, out of tiles, sleeps and its core idles.
//! Five steps below (weight 335, about a quarter of a contested core) keeps both cores busy while the UI
//! still draws smoothly as the tracer runs.

/// How many niceness steps below the UI thread the tracer's threads run on Linux.
#[cfg(target_os = "linux")]
pub const NICE_BELOW_UI: i32 = 5;

/// The priority the tracer's threads take, decided on the UI thread that starts them.
#[derive(Clone, Copy, Debug)]
pub struct TracerPriority {
    /// The niceness to take: the UI thread's plus [`NICE_BELOW_UI`], at most 19.
    #[cfg(target_os = "linux")]
    nice: i32,
}

impl TracerPriority {
    /// Below the calling thread (the UI's): [`NICE_BELOW_UI`] steps on Linux, where niceness is per thread, so
    /// a viewer started with `nice` keeps its tracer below itself; the lowest priority elsewhere.
    pub fn below_caller() -> Self {
        #[cfg(target_os = "linux")]
        {
            let ui = rustix::process::getpriority_process(None).unwrap_or(0);
            Self { nice: (ui + NICE_BELOW_UI).min(19) }
        }
        #[cfg(not(target_os = "linux"))]
        Self {}
    }

    /// Gives the calling thread this priority. It is never above the UI's, so no privilege is needed; should
    /// the system refuse anyway, the thread keeps its priority.
    pub fn apply(self) {
        #[cfg(target_os = "linux")]
        let _ = rustix::process::setpriority_process(None, self.nice);
        #[cfg(not(target_os = "linux"))]
        let _ = thread_priority::set_current_thread_priority(thread_priority::ThreadPriority::Min);
    }
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    #[test]
    fn the_tracer_runs_five_steps_below_the_caller_and_the_caller_keeps_its_niceness() {
        let ui = rustix::process::getpriority_process(None).unwrap();
        let priority = TracerPriority::below_caller();
        assert_eq!(priority.nice, (ui + NICE_BELOW_UI).min(19));
        let tracer = std::thread::spawn(move || {
            priority.apply();
            rustix::process::getpriority_process(None).unwrap()
        })
        .join()
        .unwrap();
        assert_eq!(tracer, priority.nice, "the tracer thread took its niceness");
        assert_eq!(rustix::process::getpriority_process(None).unwrap(), ui, "the calling thread kept its own");
    }
}
