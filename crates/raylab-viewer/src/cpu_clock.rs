//! What a piece of UI work costs: the calling thread's CPU time, and the wall time it took. On two cores
//! shared with the tracer threads (and, without a GPU, with the software Vulkan driver's threads), the wall
//! time of a UI frame also counts the time the thread waited for a core; the CPU time is the work itself,
//! what a budget for the UI's cost per frame is about. Both are reported.

use std::time::{Duration, Instant};

/// A start point on both clocks.
#[derive(Clone, Copy, Debug)]
pub struct Stamp {
    wall: Instant,
    cpu: Option<Duration>,
}

/// Milliseconds of work on the calling thread, and of wall time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Cost {
    /// The thread's CPU time (the wall time where the platform has no per-thread clock).
    pub cpu_ms: f64,
    /// Wall time.
    pub wall_ms: f64,
}

impl Cost {
    /// `self` with `other` taken away (clamped at zero).
    pub fn minus(self, other: Cost) -> Cost {
        Cost { cpu_ms: (self.cpu_ms - other.cpu_ms).max(0.0), wall_ms: (self.wall_ms - other.wall_ms).max(0.0) }
    }

    /// The sum of both costs.
    pub fn plus(self, other: Cost) -> Cost {
        Cost { cpu_ms: self.cpu_ms + other.cpu_ms, wall_ms: self.wall_ms + other.wall_ms }
    }
}

impl Stamp {
    /// Both clocks now.
    pub fn now() -> Self {
        Self { wall: Instant::now(), cpu: thread_cpu_time() }
    }

    /// What the calling thread spent since `self` (which must have been taken on the same thread).
    pub fn cost(&self) -> Cost {
        let wall_ms = self.wall.elapsed().as_secs_f64() * 1e3;
        let cpu_ms = match (self.cpu, thread_cpu_time()) {
            (Some(a), Some(b)) => b.saturating_sub(a).as_secs_f64() * 1e3,
            _ => wall_ms,
        };
        Cost { cpu_ms, wall_ms }
    }
}

/// CPU time the calling thread has used.
#[cfg(target_os = "linux")]
fn thread_cpu_time() -> Option<Duration> {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
    Some(Duration::new(u64::try_from(t.tv_sec).ok()?, u32::try_from(t.tv_nsec).ok()?))
}

/// No per-thread clock here: costs fall back to wall time.
#[cfg(not(target_os = "linux"))]
fn thread_cpu_time() -> Option<Duration> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sleeping_costs_wall_time_but_little_cpu() {
        let s = Stamp::now();
        std::thread::sleep(Duration::from_millis(30));
        let c = s.cost();
        assert!(c.wall_ms >= 30.0, "{c:?}");
        if cfg!(target_os = "linux") {
            assert!(c.cpu_ms < 10.0, "a sleeping thread does no work: {c:?}");
        }
    }

    #[test]
    fn busy_work_costs_cpu_time() {
        let s = Stamp::now();
        let mut x = 1u64;
        // Spin until 5 ms of CPU time are spent (however long other threads keep the cores).
        while s.cost().cpu_ms < 5.0 && s.wall.elapsed() < Duration::from_secs(10) {
            for _ in 0..1000 {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
            }
        }
        std::hint::black_box(x);
        let c = s.cost();
        assert!(c.cpu_ms >= 5.0 && c.cpu_ms <= c.wall_ms + 1.0, "{c:?}");
    }

    #[test]
    fn costs_subtract_and_add() {
        let a = Cost { cpu_ms: 3.0, wall_ms: 5.0 };
        let b = Cost { cpu_ms: 1.0, wall_ms: 6.0 };
        assert_eq!(a.minus(b), Cost { cpu_ms: 2.0, wall_ms: 0.0 });
        assert_eq!(a.plus(b), Cost { cpu_ms: 4.0, wall_ms: 11.0 });
    }
}
