//! Per-run summaries computed while a run is flown, not from a stored trajectory: a campaign of
//! 10^6 runs keeps a few hundred bytes per run.
//!
//! The quantities and verdicts are those of `rotorfault.papers.ke.flight_metrics` (README, "What
//! the report's verdicts mean"), judged against one constant setpoint over the last `window_s`
//! seconds of the run:
//! - `holds-position`: no divergence, and throughout the window the horizontal error is within
//!   `hold_horizontal_m` (2 m), the altitude error within `hold_altitude_m` (1 m) and the speed at
//!   most `hold_speed_m_s` (0.5 m/s);
//! - `circling`: not holding, mean horizontal speed over the window above `hold_speed_m_s` and
//!   the direction of travel (unwrapped heading over the samples moving faster than a quarter of
//!   it) turning by at least `circling_turn_rad` (90 degrees);
//! - `off-station`: neither;
//! - a divergence kind (`crashed`: it hit the ground; `tilt`, `altitude-loss`, ...): lost at
//!   `lost_at_s`.
//!
//! Those outcome codes are the ones before the verdicts; [`Outcome::verdict`] maps them to the
//! one verdict every table counts: `holds`, `circles`, `drifts` (off station), `crashed`,
//! `diverged` (any other divergence, [`Outcome::cause`] says which).
//!
//! The steady spin rate is the mean body yaw rate over the window, reported only when the run
//! settled (the same test as `flight_metrics`: from the last fault that changed an efficiency,
//! yaw rate within 5 % (at least 0.2 rad/s) and n3z within 0.02 of their window means to the
//! end, reached no later than one window before the end). Only the window (and the sample
//! before it) is buffered to decide that.
//!
//! A test in `tests/studies/test_campaign.py` checks every field against the same quantities computed
//! from full trajectories.

use nalgebra::Vector3;
use rayon::prelude::*;

use crate::cancel::Cancel;
use crate::control::Controller;
use crate::error::{Result, RfError};
use crate::flight::actuator::Actuators;
use crate::flight::fault_schedule::RotorFault;
use crate::flight::simulation::{
    simulate_observed, DivergenceKind, SimulationConfig, StepObserver,
};
use crate::flight::vehicle::Vehicle;
use crate::state::RigidBodyState;

/// The verdict thresholds (README, "What the report's verdicts mean"; the defaults are
/// `rotorfault.papers.ke`'s, checked equal by a test).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerdictCriteria {
    /// Length of the judging window at the end of a run, s.
    pub window_s: f64,
    pub hold_horizontal_m: f64,
    pub hold_altitude_m: f64,
    pub hold_speed_m_s: f64,
    pub circling_turn_rad: f64,
    /// Length of each of the two spans the spin growth compares (the window's last span and
    /// the one before it), s: the growth is measured only when the window holds both.
    pub spin_growth_span_s: f64,
}

impl Default for VerdictCriteria {
    fn default() -> Self {
        VerdictCriteria {
            window_s: 5.0,
            hold_horizontal_m: 2.0,
            hold_altitude_m: 1.0,
            hold_speed_m_s: 0.5,
            circling_turn_rad: std::f64::consts::FRAC_PI_2,
            spin_growth_span_s: 5.0,
        }
    }
}

impl VerdictCriteria {
    pub fn check(&self) -> Result<()> {
        for (field, v) in [
            ("criteria.window_s", self.window_s),
            ("criteria.hold_horizontal_m", self.hold_horizontal_m),
            ("criteria.hold_altitude_m", self.hold_altitude_m),
            ("criteria.hold_speed_m_s", self.hold_speed_m_s),
            ("criteria.circling_turn_rad", self.circling_turn_rad),
            ("criteria.spin_growth_span_s", self.spin_growth_span_s),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(RfError::invalid(
                    field,
                    format!("must be > 0 and finite, got {v}"),
                ));
            }
        }
        Ok(())
    }
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    HoldsPosition,
    Circling,
    OffStation,
    Lost(DivergenceKind),
}

/// The one verdict on a whole run (`rotorfault.flight.outcomes`): only `Holds` is a success.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Within the hold band of the setpoint, slower than the hold speed, throughout the window.
    Holds,
    /// Airborne to the end but neither holding nor circling (away, sinking, moving off).
    Drifts,
    /// Not holding, moving with the direction of travel turning by the circling turn or more.
    Circles,
    /// Hit the ground.
    Crashed,
    /// Lost another way (the divergence kind says how).
    Diverged,
}

impl Verdict {
    /// The kebab-case name (`holds`, `drifts`, `circles`, `crashed`, `diverged`).
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Holds => "holds",
            Verdict::Drifts => "drifts",
            Verdict::Circles => "circles",
            Verdict::Crashed => "crashed",
            Verdict::Diverged => "diverged",
        }
    }
}

impl Outcome {
    /// The kebab-case code (`holds-position`, `circling`, `off-station`, or the divergence's):
    /// the codes before the verdicts, kept for one release.
    pub fn name(self) -> &'static str {
        match self {
            Outcome::HoldsPosition => "holds-position",
            Outcome::Circling => "circling",
            Outcome::OffStation => "off-station",
            Outcome::Lost(kind) => kind.name(),
        }
    }

    /// The verdict: decided here once for every campaign run (`flight_metrics` computes the same
    /// from a full trajectory, tested equal).
    pub fn verdict(self) -> Verdict {
        match self {
            Outcome::HoldsPosition => Verdict::Holds,
            Outcome::Circling => Verdict::Circles,
            Outcome::OffStation => Verdict::Drifts,
            Outcome::Lost(DivergenceKind::Crashed) => Verdict::Crashed,
            Outcome::Lost(_) => Verdict::Diverged,
        }
    }

    /// How a lost run was lost (the divergence kind's code), `None` for a run flown to the end.
    pub fn cause(self) -> Option<&'static str> {
        match self {
            Outcome::Lost(kind) => Some(kind.name()),
            _ => None,
        }
    }
}

/// One run in a few hundred bytes. Window values and the steady values are NaN for a lost run
/// (its track stops at the loss); the steady values also when the run did not settle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSummary {
    pub outcome: Outcome,
    /// When the run was lost (NaN: not lost).
    pub lost_at_s: f64,
    /// From the first fault that changed an efficiency to the loss (NaN: not lost, or lost
    /// without a fault).
    pub time_to_loss_s: f64,
    /// Largest drop below the starting altitude over the run (up to the loss), m.
    pub max_altitude_loss_m: f64,
    pub max_horizontal_error_m: f64,
    /// At the last row (the end, or the loss).
    pub final_horizontal_error_m: f64,
    pub final_altitude_error_m: f64,
    pub window_horizontal_error_m: f64,
    pub window_altitude_error_m: f64,
    pub window_speed_m_s: f64,
    pub window_mean_horizontal_speed_m_s: f64,
    /// Largest angle between body z and world z (down), rad.
    pub peak_tilt_rad: f64,
    /// Mean body yaw rate over the window when settled, rad/s.
    pub steady_spin_rad_s: f64,
    /// Mean n3z over the window when settled.
    pub steady_n3z: f64,
    /// How much the body yaw-rate magnitude grew at the window's end: mean |r| over its last
    /// `spin_growth_span_s` minus mean |r| over the span before, rad/s (a spin that keeps
    /// speeding up is a drift; a damped spin settles to ~0). NaN for a lost run or a window
    /// shorter than two spans.
    pub window_spin_growth_rad_s: f64,
    /// Mean |r| over the window's last `spin_growth_span_s` (NaN when the growth is), rad/s.
    pub window_final_spin_rad_s: f64,
    /// Largest rotor command (finite ones), in the actuator's unit (N for fixed pitch).
    pub peak_command: f64,
    /// Time with any rotor commanded at or beyond its upper bound, s.
    pub saturated_s: f64,
    /// How long the run flew (its end or its loss), s.
    pub flown_s: f64,
}

/// The observer that builds a [`RunSummary`] while the simulator flies.
pub struct SummaryObserver {
    criteria: VerdictCriteria,
    setpoint_m: Vector3<f64>,
    window_start_s: f64,
    upper: Vec<f64>,
    start_altitude_m: Option<f64>,
    rows: usize,
    max_altitude_loss_m: f64,
    max_horizontal_error_m: f64,
    last_horizontal_m: f64,
    last_vertical_m: f64,
    peak_n3z_tilt_rad: f64,
    peak_command: f64,
    saturated_s: f64,
    /// (time, saturated) of the previous row: its command held until this row.
    previous: Option<(f64, bool)>,
    // Window.
    window_horizontal_m: f64,
    window_vertical_m: f64,
    window_speed_m_s: f64,
    window_h_speed_sum: f64,
    window_rows: usize,
    moving: usize,
    heading_raw: f64,
    heading_correction: f64,
    heading_min: f64,
    heading_max: f64,
    /// (t, yaw rate, n3z) of the window rows, preceded by the row before the window.
    spin: Vec<(f64, f64, f64)>,
    before_window: Option<(f64, f64, f64)>,
}

impl SummaryObserver {
    /// For a run of `duration_s` held at `setpoint_m`; `upper` the command bounds per channel.
    pub fn new(
        criteria: VerdictCriteria,
        setpoint_m: Vector3<f64>,
        duration_s: f64,
        upper: Vec<f64>,
        dt_s: f64,
    ) -> Self {
        let window_rows = (criteria.window_s / dt_s).ceil().min(1e7) as usize + 2;
        SummaryObserver {
            criteria,
            setpoint_m,
            window_start_s: duration_s - criteria.window_s,
            upper,
            start_altitude_m: None,
            rows: 0,
            max_altitude_loss_m: f64::NEG_INFINITY,
            max_horizontal_error_m: f64::NEG_INFINITY,
            last_horizontal_m: f64::NAN,
            last_vertical_m: f64::NAN,
            peak_n3z_tilt_rad: f64::NEG_INFINITY,
            peak_command: f64::NEG_INFINITY,
            saturated_s: 0.0,
            previous: None,
            window_horizontal_m: f64::NEG_INFINITY,
            window_vertical_m: f64::NEG_INFINITY,
            window_speed_m_s: f64::NEG_INFINITY,
            window_h_speed_sum: 0.0,
            window_rows: 0,
            moving: 0,
            heading_raw: 0.0,
            heading_correction: 0.0,
            heading_min: f64::INFINITY,
            heading_max: f64::NEG_INFINITY,
            spin: Vec::with_capacity(window_rows),
            before_window: None,
        }
    }

    /// The summary, given how the run ended, its faults, the efficiency it started with (after
    /// faults at t = 0) and its end time.
    pub fn finish(
        self,
        divergence: Option<(f64, DivergenceKind)>,
        faults: &[RotorFault],
        initial_efficiency: &[f64],
        end_s: f64,
    ) -> RunSummary {
        let nan = f64::NAN;
        // numpy's max over rows: NaN when any row is NaN (a lost run's last row never is).
        let first_fault = effective_fault_times(faults, initial_efficiency, end_s);
        let last_fault = first_fault.last().copied().unwrap_or(0.0).max(0.0);
        let mut summary = RunSummary {
            outcome: Outcome::OffStation,
            lost_at_s: nan,
            time_to_loss_s: nan,
            max_altitude_loss_m: self.max_altitude_loss_m,
            max_horizontal_error_m: self.max_horizontal_error_m,
            final_horizontal_error_m: self.last_horizontal_m,
            final_altitude_error_m: self.last_vertical_m,
            window_horizontal_error_m: nan,
            window_altitude_error_m: nan,
            window_speed_m_s: nan,
            window_mean_horizontal_speed_m_s: nan,
            peak_tilt_rad: self.peak_n3z_tilt_rad,
            steady_spin_rad_s: nan,
            steady_n3z: nan,
            window_spin_growth_rad_s: nan,
            window_final_spin_rad_s: nan,
            peak_command: if self.peak_command.is_finite() {
                self.peak_command
            } else {
                nan
            },
            saturated_s: self.saturated_s,
            flown_s: end_s,
        };
        if let Some((time_s, kind)) = divergence {
            summary.outcome = Outcome::Lost(kind);
            summary.lost_at_s = time_s;
            if let Some(&first) = first_fault.first() {
                summary.time_to_loss_s = time_s - first;
            }
            return summary;
        }
        if self.window_rows == 0 {
            return summary;
        }
        let c = &self.criteria;
        let mean_h_speed = self.window_h_speed_sum / self.window_rows as f64;
        summary.window_horizontal_error_m = self.window_horizontal_m;
        summary.window_altitude_error_m = self.window_vertical_m;
        summary.window_speed_m_s = self.window_speed_m_s;
        summary.window_mean_horizontal_speed_m_s = mean_h_speed;
        let turn = if self.moving < 2 {
            0.0
        } else {
            self.heading_max - self.heading_min
        };
        summary.outcome = if self.window_horizontal_m <= c.hold_horizontal_m
            && self.window_vertical_m <= c.hold_altitude_m
            && self.window_speed_m_s <= c.hold_speed_m_s
        {
            Outcome::HoldsPosition
        } else if mean_h_speed > c.hold_speed_m_s && turn >= c.circling_turn_rad {
            Outcome::Circling
        } else {
            Outcome::OffStation
        };
        // Steady values: means over the window, then the settle test on the window and the row
        // before it (an earlier unsettled row settles no later than that row).
        if let Some((growth, last)) =
            spin_growth(&self.spin, end_s, c.window_s, c.spin_growth_span_s)
        {
            summary.window_spin_growth_rad_s = growth;
            summary.window_final_spin_rad_s = last;
        }
        let n = self.spin.len() as f64;
        let r = self.spin.iter().map(|s| s.1).sum::<f64>() / n;
        let n3z = self.spin.iter().map(|s| s.2).sum::<f64>() / n;
        let band = (0.05 * r.abs()).max(0.2);
        let rows: Vec<(f64, f64, f64)> = self
            .before_window
            .into_iter()
            .chain(self.spin.iter().copied())
            .collect();
        let unsettled = |s: &(f64, f64, f64)| (s.1 - r).abs() > band || (s.2 - n3z).abs() > 0.02;
        let last_unsettled = rows.iter().rposition(|s| s.0 >= last_fault && unsettled(s));
        let settled_from = match last_unsettled {
            None => {
                // No unsettled row in the buffer: settled from the last fault, or from a row no
                // later than the one before the window.
                last_fault
            }
            Some(i) if i + 1 < rows.len() => rows[i + 1].0,
            Some(_) => f64::INFINITY,
        };
        if settled_from <= end_s - c.window_s + 1e-9 {
            summary.steady_spin_rad_s = r;
            summary.steady_n3z = n3z;
        }
        summary
    }
}

/// (growth, last-span mean) of |yaw rate| over the window's samples `spin` (t, r, n3z) of a
/// run that ended at `end_s`: mean |r| over (end - span, end] minus mean |r| over
/// (end - 2 span, end - span]; `None` when the window is shorter than two spans or a span has no
/// sample.
fn spin_growth(
    spin: &[(f64, f64, f64)],
    end_s: f64,
    window_s: f64,
    span_s: f64,
) -> Option<(f64, f64)> {
    // The 1e-9 s tolerance accepts a window of exactly two spans built from a sampled grid.
    if window_s + 1e-9 < 2.0 * span_s {
        return None;
    }
    let split = end_s - span_s;
    let start = end_s - 2.0 * span_s;
    let (mut before, mut n_before, mut last, mut n_last) = (0.0, 0usize, 0.0, 0usize);
    for &(t, r, _) in spin {
        if t > split + 1e-9 {
            last += r.abs();
            n_last += 1;
        } else if t > start + 1e-9 {
            before += r.abs();
            n_before += 1;
        }
    }
    if n_before == 0 || n_last == 0 {
        return None;
    }
    let last = last / n_last as f64;
    Some((last - before / n_before as f64, last))
}

/// Times of the faults that changed a rotor's efficiency by `end_s` (`flight_metrics`'s
/// `effective_fault_times`): in time order, a no-op entry is not an event.
fn effective_fault_times(
    faults: &[RotorFault],
    initial_efficiency: &[f64],
    end_s: f64,
) -> Vec<f64> {
    let mut sorted = faults.to_vec();
    sorted.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    let mut current = initial_efficiency.to_vec();
    // The initial efficiency already has the faults at t <= 0 applied.
    let mut times = Vec::new();
    for f in sorted {
        if f.time_s > end_s {
            break;
        }
        if let Some(e) = current.get_mut(f.rotor) {
            if *e != f.efficiency {
                times.push(f.time_s);
                *e = f.efficiency;
            }
        }
    }
    times
}

impl StepObserver for SummaryObserver {
    fn step(&mut self, t_s: f64, state: &RigidBodyState, command: &[f64], _efficiency: &[f64]) {
        let p = &state.position_m;
        let start = *self.start_altitude_m.get_or_insert(-p.z);
        self.rows += 1;
        let ex = p.x - self.setpoint_m.x;
        let ey = p.y - self.setpoint_m.y;
        let horizontal = ex.hypot(ey);
        let vertical = (p.z - self.setpoint_m.z).abs();
        self.max_altitude_loss_m = self.max_altitude_loss_m.max(start - (-p.z));
        self.max_horizontal_error_m = self.max_horizontal_error_m.max(horizontal);
        self.last_horizontal_m = horizontal;
        self.last_vertical_m = vertical;
        let n3z = state.primary_axis().z;
        self.peak_n3z_tilt_rad = self.peak_n3z_tilt_rad.max(n3z.clamp(-1.0, 1.0).acos());
        let mut saturated = false;
        for (c, u) in command.iter().zip(&self.upper) {
            if c.is_finite() {
                self.peak_command = self.peak_command.max(*c);
                saturated |= c >= u;
            }
        }
        if let Some((t_prev, sat_prev)) = self.previous {
            if sat_prev {
                self.saturated_s += t_s - t_prev;
            }
        }
        self.previous = Some((t_s, saturated));
        let yaw_rate = state.omega_rad_s.z;
        if t_s >= self.window_start_s {
            let v = &state.velocity_m_s;
            let h_speed = v.x.hypot(v.y);
            self.window_horizontal_m = self.window_horizontal_m.max(horizontal);
            self.window_vertical_m = self.window_vertical_m.max(vertical);
            self.window_speed_m_s = self.window_speed_m_s.max(v.norm());
            self.window_h_speed_sum += h_speed;
            self.window_rows += 1;
            if h_speed > self.criteria.hold_speed_m_s / 4.0 {
                // numpy.unwrap, one sample at a time.
                let raw = v.y.atan2(v.x);
                if self.moving > 0 {
                    let pi = std::f64::consts::PI;
                    let dd = raw - self.heading_raw;
                    let mut ddmod = (dd + pi).rem_euclid(2.0 * pi) - pi;
                    if ddmod == -pi && dd > 0.0 {
                        ddmod = pi;
                    }
                    if dd.abs() >= pi {
                        self.heading_correction += ddmod - dd;
                    }
                }
                self.heading_raw = raw;
                let unwrapped = raw + self.heading_correction;
                self.heading_min = self.heading_min.min(unwrapped);
                self.heading_max = self.heading_max.max(unwrapped);
                self.moving += 1;
            }
            self.spin.push((t_s, yaw_rate, n3z));
        } else {
            self.before_window = Some((t_s, yaw_rate, n3z));
        }
    }
}

/// One run of a summary batch: its own vehicle, actuators (settled), controller, faults, start,
/// settings (wind, noise seed) and setpoint.
pub struct SummaryRun {
    pub vehicle: Vehicle,
    pub actuators: Actuators,
    pub controller: Box<dyn Controller>,
    pub initial_efficiency: Vec<f64>,
    pub faults: Vec<RotorFault>,
    pub x0: RigidBodyState,
    pub config: SimulationConfig,
    pub setpoint_m: Vector3<f64>,
}

/// Flies one run, keeping only its summary (the trajectory is thinned to its first and last
/// rows whatever `config.record_every` says), checking `cancel` once per control period.
pub fn simulate_summary(
    mut run: SummaryRun,
    criteria: &VerdictCriteria,
    cancel: &Cancel,
) -> Result<RunSummary> {
    criteria.check()?;
    let mut config = run.config;
    config.record_every = usize::MAX;
    let count = run.actuators.channels() * run.actuators.rotor_count();
    let mut upper = vec![0.0; count];
    run.actuators.saturate(&vec![f64::MAX; count], &mut upper);
    let mut observer = SummaryObserver::new(
        *criteria,
        run.setpoint_m,
        config.duration_s,
        upper,
        config.dt_s,
    );
    let trajectory = simulate_observed(
        &run.vehicle,
        run.actuators,
        run.controller.as_mut(),
        &run.initial_efficiency,
        &run.faults,
        run.x0,
        &config,
        &mut observer,
        cancel,
    )?;
    let end = trajectory.t_s.last().copied().unwrap_or(0.0);
    let m = run.initial_efficiency.len();
    let start_efficiency = trajectory
        .efficiency
        .get(..m)
        .unwrap_or(&run.initial_efficiency);
    Ok(observer.finish(
        trajectory.divergence.map(|d| (d.time_s, d.kind)),
        &run.faults,
        start_efficiency,
        end,
    ))
}

/// Many runs in parallel (rayon), summaries in input order.
pub fn simulate_summaries(
    runs: Vec<SummaryRun>,
    criteria: &VerdictCriteria,
    cancel: &Cancel,
) -> Result<Vec<RunSummary>> {
    criteria.check()?;
    runs.into_par_iter()
        .map(|run| simulate_summary(run, criteria, cancel))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::ZeroCommand;
    use crate::flight::actuator::{FixedPitch, Lag};
    use crate::flight::vehicle::Drag;

    /// Rotors off from `height_m` above the ground (at rest, level), judged against the start.
    fn free_fall_from(height_m: f64, duration_s: f64) -> SummaryRun {
        let airframe = crate::fixtures::preset("quad-x");
        let mut config = SimulationConfig::new(0.0025, 2, duration_s);
        config.limits.max_altitude_loss_m = 20.0;
        SummaryRun {
            vehicle: Vehicle::new(&airframe, Drag::default()).unwrap(),
            actuators: Actuators::FixedPitch(FixedPitch::new(&airframe, Lag::none(), 0.0).unwrap()),
            controller: Box::new(ZeroCommand { count: 4 }),
            initial_efficiency: vec![1.0; 4],
            faults: vec![RotorFault {
                rotor: 0,
                time_s: 0.5,
                efficiency: 0.0,
            }],
            x0: RigidBodyState {
                position_m: Vector3::new(0.0, 0.0, -height_m),
                ..RigidBodyState::at_rest()
            },
            config,
            setpoint_m: Vector3::new(0.0, 0.0, -height_m),
        }
    }

    /// 100 m up: these falls end before the ground.
    fn free_fall(duration_s: f64) -> SummaryRun {
        free_fall_from(100.0, duration_s)
    }

    #[test]
    fn a_fall_to_the_ground_is_counted_crashed() {
        // 10 m of free fall reach the ground at sqrt(20 / g) s, before the 20 m limit.
        let s = simulate_summary(free_fall_from(10.0, 10.0), &VerdictCriteria::default(), &crate::Cancel::never()).unwrap();
        let g = crate::fixtures::preset("quad-x").gravity_m_s2();
        assert_eq!(s.outcome, Outcome::Lost(DivergenceKind::Crashed));
        assert_eq!(s.outcome.name(), "crashed");
        assert_eq!(s.outcome.verdict(), Verdict::Crashed);
        assert_eq!(s.outcome.cause(), Some("crashed"));
        assert!((s.lost_at_s - (20.0 / g).sqrt()).abs() < 1e-9);
        assert!((s.max_altitude_loss_m - 10.0).abs() < 1e-9);
        assert!((s.final_altitude_error_m - 10.0).abs() < 1e-9);
        assert!(s.window_speed_m_s.is_nan());
    }

    #[test]
    fn free_fall_is_lost_at_the_analytic_time() {
        // 20 m of free fall take sqrt(40 / g) s (the located crossing, to 1e-12 s).
        let s = simulate_summary(
            free_fall(10.0),
            &VerdictCriteria::default(),
            &Cancel::never(),
        )
        .unwrap();
        let g = crate::fixtures::preset("quad-x").gravity_m_s2();
        let expected = (40.0 / g).sqrt();
        assert_eq!(s.outcome, Outcome::Lost(DivergenceKind::AltitudeLoss));
        assert_eq!(s.outcome.verdict().name(), "diverged");
        assert_eq!(s.outcome.cause(), Some("altitude-loss"));
        assert!((s.lost_at_s - expected).abs() < 1e-12);
        assert!((s.time_to_loss_s - (expected - 0.5)).abs() < 1e-12);
        assert!((s.max_altitude_loss_m - 20.0).abs() < 1e-9);
        assert!(s.window_speed_m_s.is_nan());
        assert_eq!(s.peak_command, 0.0);
        assert_eq!(s.saturated_s, 0.0);
    }

    #[test]
    fn a_short_fall_is_off_station_with_window_values() {
        // 1 s of free fall: 0.5 g m down, speed g m/s, all in a 5 s window.
        let s = simulate_summary(
            free_fall(1.0),
            &VerdictCriteria::default(),
            &Cancel::never(),
        )
        .unwrap();
        let g = crate::fixtures::preset("quad-x").gravity_m_s2();
        // A vehicle falling freely for the whole window is not a success: it drifts.
        assert_eq!(s.outcome, Outcome::OffStation);
        assert_eq!(s.outcome.verdict(), Verdict::Drifts);
        assert_eq!(s.outcome.cause(), None);
        assert!((s.max_altitude_loss_m - 0.5 * g).abs() < 1e-9);
        assert!((s.window_speed_m_s - g).abs() < 1e-9);
        assert_eq!(s.window_mean_horizontal_speed_m_s, 0.0);
        assert!((s.final_altitude_error_m - 0.5 * g).abs() < 1e-9);
    }

    /// The observer fed hovering rows at the setpoint every 0.01 s for 20 s, yaw rate `r(t)`,
    /// judged over a 10 s window (two 5 s spans).
    fn spin_summary(r: impl Fn(f64) -> f64) -> RunSummary {
        let criteria = VerdictCriteria {
            window_s: 10.0,
            ..VerdictCriteria::default()
        };
        let dt_s = 0.01;
        let mut observer = SummaryObserver::new(criteria, Vector3::zeros(), 20.0, vec![1.0; 4], dt_s);
        for k in 0..=2000 {
            let t = k as f64 * dt_s;
            let mut state = RigidBodyState::at_rest();
            state.omega_rad_s.z = r(t);
            observer.step(t, &state, &[0.5; 4], &[1.0; 4]);
        }
        observer.finish(None, &[], &[1.0; 4], 20.0)
    }

    #[test]
    fn a_constant_spin_does_not_grow() {
        let s = spin_summary(|_| -7.0);
        assert_eq!(s.outcome, Outcome::HoldsPosition);
        assert!(s.window_spin_growth_rad_s.abs() < 1e-12, "{}", s.window_spin_growth_rad_s);
        assert!((s.window_final_spin_rad_s - 7.0).abs() < 1e-12);
    }

    #[test]
    fn a_linear_spin_up_grows_by_its_rate_times_the_span() {
        // r = -(1 + a t): |r| means over two adjacent 5 s spans (500 samples each, the same
        // grid shifted by 5 s) differ by exactly a * 5 s; the last span's mean is |r| at its
        // middle sample spacing: 1 + a (17.5 + 0.005) s.
        let a = 0.8;
        let s = spin_summary(|t| -(1.0 + a * t));
        assert!((s.window_spin_growth_rad_s - a * 5.0).abs() < 1e-9, "{}", s.window_spin_growth_rad_s);
        assert!((s.window_final_spin_rad_s - (1.0 + a * 17.505)).abs() < 1e-9);
    }

    #[test]
    fn spin_growth_needs_two_spans_in_the_window() {
        // The default 5 s window holds one span: not measured. A lost run: not measured.
        let s = simulate_summary(free_fall(6.0), &VerdictCriteria::default(), &Cancel::never()).unwrap();
        assert!(s.window_spin_growth_rad_s.is_nan());
        assert!(s.window_final_spin_rad_s.is_nan());
        let long = VerdictCriteria { window_s: 10.0, ..VerdictCriteria::default() };
        let lost = simulate_summary(free_fall(10.0), &long, &Cancel::never()).unwrap();
        assert!(matches!(lost.outcome, Outcome::Lost(_)));
        assert!(lost.window_spin_growth_rad_s.is_nan());
    }

    #[test]
    fn bad_criteria_are_named() {
        let criteria = VerdictCriteria {
            window_s: 0.0,
            ..VerdictCriteria::default()
        };
        let err = simulate_summary(free_fall(1.0), &criteria, &Cancel::never())
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("criteria.window_s"), "{err}");
        let criteria = VerdictCriteria {
            spin_growth_span_s: f64::NAN,
            ..VerdictCriteria::default()
        };
        let err = simulate_summary(free_fall(1.0), &criteria, &Cancel::never())
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("criteria.spin_growth_span_s"), "{err}");
    }
}
