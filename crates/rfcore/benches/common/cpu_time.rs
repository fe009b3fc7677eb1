//! CPU-time medians for the benches' summary lines (shared by `sensors` and `sensing`).

use std::time::Instant;

/// This thread's CPU time, s: the first field of `/proc/thread-self/schedstat` (ns on the CPU),
/// which other processes on a loaded machine do not inflate; wall time where it is missing.
pub fn cpu_time_s(wall: Instant) -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or_else(|| wall.elapsed().as_secs_f64(), |ns| ns * 1e-9)
}

/// Median CPU time of `f` over `reps` calls, s.
#[allow(dead_code)] // Used by the `sensors` bench only.
pub fn median_s(reps: usize, mut f: impl FnMut()) -> f64 {
    let origin = Instant::now();
    let mut times: Vec<f64> = (0..reps)
        .map(|_| {
            let start = cpu_time_s(origin);
            f();
            cpu_time_s(origin) - start
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[reps / 2]
}

/// Median CPU times of `f` and `g` over `reps` calls each, taken alternately (f, g, f, g, ...):
/// a ratio of the two then sees the same load on a shared machine, s.
#[allow(dead_code)] // Used by the `sensing` bench only.
pub fn median_pair_s(reps: usize, mut f: impl FnMut(), mut g: impl FnMut()) -> (f64, f64) {
    let origin = Instant::now();
    let timed = |h: &mut dyn FnMut()| {
        let start = cpu_time_s(origin);
        h();
        cpu_time_s(origin) - start
    };
    let (mut a, mut b): (Vec<f64>, Vec<f64>) =
        (0..reps).map(|_| (timed(&mut f), timed(&mut g))).unzip();
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    (a[reps / 2], b[reps / 2])
}
