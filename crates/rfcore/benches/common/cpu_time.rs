//! CPU-time medians for the benches' summary lines (shared by `sensors` and `sensing`).
//!
//! The clocks are `clock_gettime`'s CPU-time clocks (nanosecond resolution), which other
//! processes on a loaded machine do not inflate. `/proc/thread-self/schedstat`, used before,
//! advances in scheduler ticks on the project's VM (4 ms steps: a 4 ms flight timed 8.0, 12.0 or
//! 16.0 ms), so a median of single flights measured the tick, not the flight.

use std::time::Instant;

fn clock_s(clock: libc::clockid_t) -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid, writable timespec; the clock ids are POSIX constants.
    let status = unsafe { libc::clock_gettime(clock, &mut t) };
    assert_eq!(status, 0, "clock_gettime({clock}) failed");
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

/// This thread's CPU time, s.
pub fn thread_cpu_s() -> f64 {
    clock_s(libc::CLOCK_THREAD_CPUTIME_ID)
}

/// This process's CPU time (every thread: rayon's workers too), s.
#[allow(dead_code)] // Used by the `sensing` bench only.
pub fn process_cpu_s() -> f64 {
    clock_s(libc::CLOCK_PROCESS_CPUTIME_ID)
}

/// Median thread CPU time of `f` over `reps` calls, s.
#[allow(dead_code)] // Used by the `sensors` bench only.
pub fn median_s(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..reps)
        .map(|_| {
            let start = thread_cpu_s();
            f();
            thread_cpu_s() - start
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[reps / 2]
}

/// One timed call: process CPU time and wall time, s.
#[derive(Debug, Clone, Copy)]
#[allow(dead_code)] // Used by the `sensing` bench only.
pub struct Timing {
    pub cpu_s: f64,
    pub wall_s: f64,
}

/// Medians of `f` and `g` over `reps` calls each, taken alternately (f, g, f, g, ...) so that a
/// ratio of the two sees the same load on a shared machine: process CPU time (a batch runs on
/// rayon's threads) and wall time, s.
#[allow(dead_code)] // Used by the `sensing` bench only.
pub fn median_pair(reps: usize, mut f: impl FnMut(), mut g: impl FnMut()) -> (Timing, Timing) {
    let timed = |h: &mut dyn FnMut()| {
        let (cpu, wall) = (process_cpu_s(), Instant::now());
        h();
        (process_cpu_s() - cpu, wall.elapsed().as_secs_f64())
    };
    let samples: Vec<((f64, f64), (f64, f64))> =
        (0..reps).map(|_| (timed(&mut f), timed(&mut g))).collect();
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[reps / 2]
    };
    let pick = |which: fn(&((f64, f64), (f64, f64))) -> (f64, f64)| Timing {
        cpu_s: median(samples.iter().map(|s| which(s).0).collect()),
        wall_s: median(samples.iter().map(|s| which(s).1).collect()),
    };
    (pick(|s| s.0), pick(|s| s.1))
}
