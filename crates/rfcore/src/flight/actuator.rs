//! Rotor actuator models: what a rotor actually produces for what it is commanded.
//!
//! Two models sit behind one interface ([`Actuators`]): fixed-pitch rotors commanded in thrust
//! (Ke, Lanzon, Du) and variable-pitch propellers commanded in speed and blade pitch (Wang et al.
//! eq. (3)). Adding a model means adding a variant; the simulator only sees [`RotorOutput`]s.
//!
//! # Dynamics (stated once, used everywhere)
//! Every channel `a` follows the continuous first-order lag with saturation and rate limit
//!
//! `a' = clamp((sat(u) - a) / tau, -rate, rate)`
//!
//! (`sat`: the channel's bounds, a rotor cannot be asked for more than it can give; `tau = 0`
//! means no lag: with an infinite rate the state follows the command at once, with a finite
//! rate it slews at the rate limit, Lanzon's 50 N/s). The command is held between control steps
//! (zero-order hold), and for a held command this ODE has a closed-form solution
//! ([`Lag::response`]): a straight line at the rate limit while `|sat(u) - a| > rate tau`, then
//! the exponential. The simulator evaluates that solution at every RK4 stage time, so the rigid
//! body sees the actuator as it evolves *within* each substep (the coupled system is fourth order
//! where smooth; the actuator part is exact, so it is stable at any step).
//!
//! # Health
//! `health_i` in [0, 1] (Du's eta, Ke's lambda) scales what rotor i produces (a failed rotor
//! produces nothing). One rule for both models, written once in [`spin_factor`]: a rotor at
//! efficiency `eta` delivers `eta` times the thrust and reaction torque *because it turns slower*,
//! so its spin (the gyroscopic moment) is `sqrt(eta)` times the healthy spin. The actuator state
//! itself is not touched, so a controller that keeps commanding a dead rotor sees no effect, as
//! in reality.

use crate::airframe::Airframe;
use crate::error::{require_finite, require_normal, require_scale_or_zero, Result, RfError};

/// What rotor i produces right now, after efficiency is applied.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RotorOutput {
    /// Thrust along body -z (up), N (negative for a reversed variable-pitch propeller).
    pub thrust_n: f64,
    /// Reaction (drag) torque about body z (FRD), N m, signed by the spin direction.
    pub reaction_torque_nm: f64,
    /// Rotor angular velocity along body z (FRD), rad/s; feeds the gyroscopic moment.
    pub spin_rad_s: f64,
}

/// First-order lag and rate limit of one kind of channel (fixed pitch: thrust; variable pitch:
/// speed and pitch each have their own, [`VariablePitchLags`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lag {
    /// Time constant, s (0: the state follows the command at once).
    pub time_constant_s: f64,
    /// Largest rate of change, channel units per second (`f64::INFINITY`: none).
    pub rate_limit_per_s: f64,
}

impl Lag {
    pub fn none() -> Self {
        Lag {
            time_constant_s: 0.0,
            rate_limit_per_s: f64::INFINITY,
        }
    }

    /// A first-order lag with cut-off `cutoff_hz` (`tau = 1 / (2 pi f_c)`), no rate limit.
    pub fn cutoff_hz(cutoff_hz: f64) -> Self {
        Lag {
            time_constant_s: 1.0 / (2.0 * std::f64::consts::PI * cutoff_hz),
            rate_limit_per_s: f64::INFINITY,
        }
    }

    /// `rate_field` names the rate limit as the caller's API does (its unit differs by model).
    fn check(&self, prefix: &str, rate_field: &str) -> Result<()> {
        // Divided by (exp(-h / tau), the step-size guard's 1 / tau): a scale, 0 for no lag.
        require_scale_or_zero(
            &format!("{prefix}time_constant_s"),
            self.time_constant_s,
            "s",
        )?;
        let field = format!("{prefix}{rate_field}");
        // Divided by too (the end of the rate-limited line): positive and normal, or infinity.
        if self.rate_limit_per_s.is_nan()
            || self.rate_limit_per_s <= 0.0
            || !(self.rate_limit_per_s.is_normal() || self.rate_limit_per_s.is_infinite())
        {
            return Err(RfError::invalid(
                field,
                format!(
                    "must be > 0 and normal (infinity for none), got {}",
                    self.rate_limit_per_s
                ),
            ));
        }
        Ok(())
    }

    /// The channel state `elapsed_s` after `state` under the held, already saturated `target`:
    /// the exact solution of `a' = clamp((target - a) / tau, -rate, rate)` (module docs). With
    /// no lag and no rate limit the state is `target` for any `elapsed_s`, including 0 (the
    /// value just after the command changed).
    #[inline]
    pub fn response(&self, state: f64, target: f64, elapsed_s: f64) -> f64 {
        self.response_with_decay(state, target, elapsed_s, self.decay(elapsed_s))
    }

    /// `exp(-elapsed / tau)` (1 without lag): shared by every channel at one time.
    #[inline]
    fn decay(&self, elapsed_s: f64) -> f64 {
        if self.time_constant_s > 0.0 {
            (-elapsed_s / self.time_constant_s).exp()
        } else {
            1.0
        }
    }

    #[inline]
    fn response_with_decay(&self, state: f64, target: f64, elapsed_s: f64, decay: f64) -> f64 {
        let gap = target - state;
        let tau = self.time_constant_s;
        let rate = self.rate_limit_per_s;
        if elapsed_s == 0.0 && (tau > 0.0 || rate.is_finite()) {
            return state; // continuous: exactly the current state
        }
        if tau > 0.0 {
            // Rate-limited while |gap| / tau > rate: a line until the gap is rate tau, at
            // s* = (|gap| - rate tau) / rate, then the exponential from there.
            let slew = rate * tau;
            if gap.abs() <= slew {
                return target - gap * decay;
            }
            let s_star = (gap.abs() - slew) / rate;
            if elapsed_s <= s_star {
                state + gap.signum() * rate * elapsed_s
            } else {
                target - gap.signum() * slew * (-(elapsed_s - s_star) / tau).exp()
            }
        } else if rate.is_finite() {
            let step = rate * elapsed_s;
            state + gap.clamp(-step, step)
        } else {
            target
        }
    }
}

/// `exp(-elapsed / tau)` per kind of channel ([`Actuators::decay`]).
pub type Decay = [f64; 2];

/// The factor by which a rotor at efficiency `efficiency` spins relative to a healthy rotor with the
/// same command: `sqrt(efficiency)`.
///
/// Decision (physics): a rotor's thrust and reaction torque both go as the square of its speed
/// (`f = k_f Omega^2`, `q = k_m Omega^2`). The model scales both by `efficiency` (Du's column
/// scaling, including the yaw row), which is what a rotor turning at `sqrt(efficiency)` times the
/// speed produces: a weak motor, a sagging ESC or a failed one (efficiency 0: stopped, no gyroscopic
/// moment). The alternative, full speed with less thrust (a damaged blade), would leave a dead
/// rotor spinning at full speed and would not scale the reaction torque like the thrust. Both
/// actuator models use this one function.
#[inline]
pub fn spin_factor(efficiency: f64) -> f64 {
    efficiency.max(0.0).sqrt()
}

/// Fixed-pitch rotors commanded in thrust (N), bounds and spin from the airframe.
#[derive(Debug, Clone, PartialEq)]
pub struct FixedPitch {
    min_thrust_n: Vec<f64>,
    max_thrust_n: Vec<f64>,
    /// `w_i k_mu`: reaction torque per newton of thrust, signed (m).
    torque_per_thrust_m: Vec<f64>,
    /// `w_i`, for the spin direction.
    yaw_sign: Vec<f64>,
    /// Thrust coefficient `k_f` in `f = k_f omega^2` (N s^2); 0 when rotor speed is not modelled.
    thrust_coefficient_n_s2: f64,
    lag: Lag,
    thrust_n: Vec<f64>,
}

impl FixedPitch {
    /// The rules on the parameters, apart from the airframe (checked when Python makes its
    /// `FixedPitchActuator`, and again here by `new`: one rule, one message).
    pub fn check_parameters(lag: &Lag, thrust_coefficient_n_s2: f64) -> Result<()> {
        lag.check("actuator.", "rate_limit_n_s")?;
        // `sqrt(f / k_f)` is the rotor's spin: a scale, 0 when rotor speed is not modelled.
        require_scale_or_zero(
            "actuator.thrust_coefficient_n_s2",
            thrust_coefficient_n_s2,
            "N s^2 (0: rotor speed not modelled)",
        )
    }

    pub fn new(airframe: &Airframe, lag: Lag, thrust_coefficient_n_s2: f64) -> Result<Self> {
        Self::check_parameters(&lag, thrust_coefficient_n_s2)?;
        let yaw_sign: Vec<f64> = airframe
            .rotors()
            .iter()
            .map(|r| r.spin.yaw_sign())
            .collect();
        Ok(FixedPitch {
            min_thrust_n: airframe.min_thrust_n(),
            max_thrust_n: airframe.max_thrust_n(),
            torque_per_thrust_m: yaw_sign
                .iter()
                .enumerate()
                .map(|(i, w)| w * airframe.rotor_drag_torque_ratio_m(i))
                .collect(),
            yaw_sign,
            thrust_coefficient_n_s2,
            lag,
            thrust_n: vec![0.0; airframe.rotor_count()],
        })
    }
}

impl FixedPitch {
    /// `w_i k_mu` per rotor: reaction torque per newton of thrust, signed (m).
    pub(crate) fn torque_per_thrust_m(&self) -> &[f64] {
        &self.torque_per_thrust_m
    }
}

/// The speed and pitch channels' own lags (a motor's speed loop and a servo are different
/// hardware). Default: Wang et al. Sec. 4.2, "a first-order transfer function ... cut-off
/// frequency 10 Hz" for both, no rate limit (the paper gives none).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VariablePitchLags {
    /// Rotor speed channel; rate limit in speed units per second.
    pub speed: Lag,
    /// Blade pitch channel; rate limit in rad/s.
    pub pitch: Lag,
}

impl Default for VariablePitchLags {
    fn default() -> Self {
        VariablePitchLags {
            speed: Lag::cutoff_hz(10.0),
            pitch: Lag::cutoff_hz(10.0),
        }
    }
}

impl VariablePitchLags {
    pub fn check(&self) -> Result<()> {
        self.speed.check("actuator.speed_", "rate_limit_per_s")?;
        self.pitch.check("actuator.pitch_", "rate_limit_rad_s")
    }
}

/// Variable-pitch propellers (Wang et al. eq. (3)): commands are rotor speed `omega` and blade
/// pitch `alpha` per rotor (interleaved: `[omega_1, alpha_1, omega_2, ...]`), in the units the
/// coefficients use (Wang prints speeds up to 10,000). Thrust `k1 omega^2 alpha`, reaction torque
/// `k2 omega^2 + k3 omega^2 alpha^2 + k4 omega alpha`, signed by the spin direction.
#[derive(Debug, Clone, PartialEq)]
pub struct VariablePitch {
    pub coefficients: [f64; 4],
    /// Per-channel bounds, interleaved like the state: speed bounds, then pitch bounds, per rotor.
    lower: Vec<f64>,
    upper: Vec<f64>,
    /// Factor from the speed unit to rad/s for the gyroscopic moment (0: not modelled).
    pub speed_to_rad_s: f64,
    yaw_sign: Vec<f64>,
    /// `[speed, pitch]` ([`VariablePitchLags`]), indexed by channel `k % 2`.
    lags: [Lag; 2],
    /// `[omega_1, alpha_1, omega_2, alpha_2, ...]`.
    state: Vec<f64>,
}

impl VariablePitch {
    /// The rules on the parameters, apart from the airframe (checked when Python makes its
    /// `VariablePitchActuator`, and again here by `new`: one rule, one message).
    pub fn check_parameters(
        coefficients: [f64; 4],
        speed_bounds: (f64, f64),
        pitch_bounds: (f64, f64),
        speed_to_rad_s: f64,
        lags: VariablePitchLags,
    ) -> Result<()> {
        lags.check()?;
        for (i, &k) in coefficients.iter().enumerate() {
            // Python's trim and linearisation divide by them: zero or normal.
            require_normal(&format!("actuator.k{}", i + 1), k)?;
        }
        for (field, (lo, hi)) in [
            ("actuator.speed_bounds", speed_bounds),
            ("actuator.pitch_bounds", pitch_bounds),
        ] {
            require_finite(field, lo)?;
            require_finite(field, hi)?;
            if lo > hi {
                return Err(RfError::invalid(
                    field,
                    format!("lower bound {lo} exceeds upper bound {hi}"),
                ));
            }
        }
        if speed_bounds.0 < 0.0 {
            return Err(RfError::invalid(
                "actuator.speed_bounds",
                "rotor speed cannot be negative",
            ));
        }
        require_finite("actuator.speed_to_rad_s", speed_to_rad_s)
    }

    pub fn new(
        airframe: &Airframe,
        coefficients: [f64; 4],
        speed_bounds: (f64, f64),
        pitch_bounds: (f64, f64),
        speed_to_rad_s: f64,
        lags: VariablePitchLags,
    ) -> Result<Self> {
        Self::check_parameters(
            coefficients,
            speed_bounds,
            pitch_bounds,
            speed_to_rad_s,
            lags,
        )?;
        let m = airframe.rotor_count();
        Ok(VariablePitch {
            coefficients,
            lower: (0..2 * m)
                .map(|k| {
                    if k % 2 == 0 {
                        speed_bounds.0
                    } else {
                        pitch_bounds.0
                    }
                })
                .collect(),
            upper: (0..2 * m)
                .map(|k| {
                    if k % 2 == 0 {
                        speed_bounds.1
                    } else {
                        pitch_bounds.1
                    }
                })
                .collect(),
            speed_to_rad_s,
            yaw_sign: airframe
                .rotors()
                .iter()
                .map(|r| r.spin.yaw_sign())
                .collect(),
            lags: [lags.speed, lags.pitch],
            state: vec![0.0; 2 * airframe.rotor_count()],
        })
    }
}

/// The actuator models the simulator knows.
#[derive(Debug, Clone, PartialEq)]
pub enum Actuators {
    FixedPitch(FixedPitch),
    VariablePitch(VariablePitch),
}

impl Actuators {
    pub fn rotor_count(&self) -> usize {
        match self {
            Actuators::FixedPitch(a) => a.thrust_n.len(),
            Actuators::VariablePitch(a) => a.yaw_sign.len(),
        }
    }

    /// `k_f` of `f = k_f omega^2` when a rotor's speed alone gives its thrust (fixed pitch with a
    /// thrust coefficient); `None` otherwise (no rotor speed modelled, or variable pitch).
    pub fn speed_thrust_coefficient(&self) -> Option<f64> {
        match self {
            Actuators::FixedPitch(a) if a.thrust_coefficient_n_s2 > 0.0 => {
                Some(a.thrust_coefficient_n_s2)
            }
            _ => None,
        }
    }

    /// Commands per rotor: 1 (thrust) or 2 (speed, pitch).
    pub fn channels(&self) -> usize {
        match self {
            Actuators::FixedPitch(_) => 1,
            Actuators::VariablePitch(_) => 2,
        }
    }

    /// Sets the actuator state to the saturated commands, as if held forever (trimmed start).
    /// `commands` must hold `channels() * rotor_count()` values.
    pub fn settle(&mut self, commands: &[f64]) -> Result<()> {
        let count = self.channels() * self.rotor_count();
        if commands.len() != count {
            return Err(RfError::shape(
                "initial_command",
                format!("{count} entries ({} per rotor)", self.channels()),
                commands.len().to_string(),
            ));
        }
        crate::error::require_all_finite("initial_command", commands)?;
        let (state, _, lower, upper) = self.channels_mut();
        for (k, x) in state.iter_mut().enumerate() {
            *x = commands[k].clamp(lower[k], upper[k]);
        }
        Ok(())
    }

    /// Advances every channel by `dt_s` under `commands` (`channels() * rotor_count()`), held:
    /// the exact solution of the lag ODE (module docs).
    pub fn advance(&mut self, commands: &[f64], dt_s: f64) {
        let decay = self.decay(dt_s);
        let (state, lags, lower, upper) = self.channels_mut();
        let kinds = lags.len();
        for (k, x) in state.iter_mut().enumerate() {
            let target = commands[k].clamp(lower[k], upper[k]);
            let kind = k % kinds;
            *x = lags[kind].response_with_decay(*x, target, dt_s, decay[kind]);
        }
    }

    /// Writes into `out` every channel's state `elapsed_s` after the current state under the
    /// saturated targets `targets` (see [`Actuators::saturate`]), without changing `self`.
    #[inline]
    pub fn response(&self, targets: &[f64], elapsed_s: f64, out: &mut [f64]) {
        self.response_with_decay(targets, elapsed_s, self.decay(elapsed_s), out);
    }

    /// `exp(-elapsed / time_constant)` (1 without lag) per kind of channel (entry `k % channels()`
    /// for channel `k`; fixed pitch uses entry 0), for [`Actuators::response_with_decay`]: lets a
    /// caller that takes many equal steps compute it once.
    #[inline]
    pub fn decay(&self, elapsed_s: f64) -> Decay {
        let lags = self.lags();
        [
            lags[0].decay(elapsed_s),
            lags[lags.len() - 1].decay(elapsed_s),
        ]
    }

    /// [`Actuators::response`] with `decay = self.decay(elapsed_s)` given.
    #[inline]
    pub fn response_with_decay(
        &self,
        targets: &[f64],
        elapsed_s: f64,
        decay: Decay,
        out: &mut [f64],
    ) {
        match self {
            Actuators::FixedPitch(a) => {
                for ((o, &x), &target) in out.iter_mut().zip(&a.thrust_n).zip(targets) {
                    *o = a.lag.response_with_decay(x, target, elapsed_s, decay[0]);
                }
            }
            Actuators::VariablePitch(a) => {
                let [speed, pitch] = a.lags;
                let pairs = out
                    .chunks_exact_mut(2)
                    .zip(a.state.chunks_exact(2))
                    .zip(targets.chunks_exact(2));
                for ((o, x), target) in pairs {
                    o[0] = speed.response_with_decay(x[0], target[0], elapsed_s, decay[0]);
                    o[1] = pitch.response_with_decay(x[1], target[1], elapsed_s, decay[1]);
                }
            }
        }
    }

    /// The commands clipped to each channel's bounds: what the channels move towards.
    pub fn saturate(&self, commands: &[f64], targets: &mut [f64]) {
        let (lower, upper) = match self {
            Actuators::FixedPitch(a) => (&a.min_thrust_n, &a.max_thrust_n),
            Actuators::VariablePitch(a) => (&a.lower, &a.upper),
        };
        for (k, t) in targets.iter_mut().enumerate() {
            *t = commands[k].clamp(lower[k], upper[k]);
        }
    }

    /// Replaces the channel states (`channels() * rotor_count()` values, e.g. from
    /// [`Actuators::response`]).
    pub fn set_state(&mut self, states: &[f64]) {
        let (state, _, _, _) = self.channels_mut();
        state.copy_from_slice(states);
    }

    /// `true` when the channels follow the (saturated) command at once: no lag, no rate limit.
    pub fn is_instant(&self) -> bool {
        self.lags()
            .iter()
            .all(|lag| lag.time_constant_s == 0.0 && lag.rate_limit_per_s == f64::INFINITY)
    }

    /// The shortest positive lag time constant over the channels, s (0: no channel lags): the
    /// fastest actuator rate the step-size guard must resolve.
    pub fn time_constant_s(&self) -> f64 {
        self.lags()
            .iter()
            .map(|lag| lag.time_constant_s)
            .filter(|&tau| tau > 0.0)
            .fold(
                0.0,
                |acc: f64, tau| if acc == 0.0 { tau } else { acc.min(tau) },
            )
    }

    /// The lag and rate limit of each kind of channel: one for fixed pitch (thrust), two for
    /// variable pitch (speed, pitch); channel `k` uses entry `k % channels()`.
    pub fn lags(&self) -> &[Lag] {
        match self {
            Actuators::FixedPitch(a) => std::slice::from_ref(&a.lag),
            Actuators::VariablePitch(a) => &a.lags[..],
        }
    }

    /// Every channel's state, the model's lags and the per-channel bounds: the one place that
    /// knows how a model lays out its channels.
    fn channels_mut(&mut self) -> (&mut [f64], &[Lag], &[f64], &[f64]) {
        match self {
            Actuators::FixedPitch(a) => (
                &mut a.thrust_n,
                std::slice::from_ref(&a.lag),
                &a.min_thrust_n,
                &a.max_thrust_n,
            ),
            Actuators::VariablePitch(a) => (&mut a.state, &a.lags[..], &a.lower, &a.upper),
        }
    }

    /// What rotor `i` produces with efficiency `efficiency` (module docs).
    pub fn output(&self, i: usize, efficiency: f64) -> RotorOutput {
        self.output_at(self.state(), i, efficiency)
    }

    /// Calls `f` with what each rotor produces (rotor 1 first) with the channels at `states`
    /// and efficiency `efficiency`: [`Actuators::output_at`] for every rotor, the model chosen once.
    #[inline(always)]
    pub fn for_each_output(
        &self,
        states: &[f64],
        efficiency: &[f64],
        mut f: impl FnMut(RotorOutput),
    ) {
        match self {
            Actuators::FixedPitch(a) => {
                let rotors = states
                    .iter()
                    .zip(efficiency)
                    .zip(a.torque_per_thrust_m.iter().zip(&a.yaw_sign));
                for ((&command, &eta), (&torque_per_thrust, &yaw_sign)) in rotors {
                    let thrust = eta * command;
                    let spin = if a.thrust_coefficient_n_s2 > 0.0 {
                        (command.max(0.0) / a.thrust_coefficient_n_s2).sqrt() * spin_factor(eta)
                    } else {
                        0.0
                    };
                    f(RotorOutput {
                        thrust_n: thrust,
                        reaction_torque_nm: torque_per_thrust * thrust,
                        spin_rad_s: -yaw_sign * spin,
                    });
                }
            }
            Actuators::VariablePitch(_) => {
                for (i, &eta) in efficiency.iter().enumerate() {
                    f(self.output_at(states, i, eta));
                }
            }
        }
    }

    /// What rotor `i` produces with efficiency `efficiency` when the channels are at `states` (laid out
    /// like [`Actuators::state`]).
    #[inline(always)]
    pub fn output_at(&self, states: &[f64], i: usize, efficiency: f64) -> RotorOutput {
        match self {
            Actuators::FixedPitch(a) => {
                let thrust = efficiency * states[i];
                // Spin of the healthy rotor at this command, then the one efficiency rule.
                let spin = if a.thrust_coefficient_n_s2 > 0.0 {
                    (states[i].max(0.0) / a.thrust_coefficient_n_s2).sqrt()
                        * spin_factor(efficiency)
                } else {
                    0.0
                };
                RotorOutput {
                    thrust_n: thrust,
                    reaction_torque_nm: a.torque_per_thrust_m[i] * thrust,
                    // Anticlockwise seen from above (w = +1) spins about body -z (FRD).
                    spin_rad_s: -a.yaw_sign[i] * spin,
                }
            }
            Actuators::VariablePitch(a) => {
                let [k1, k2, k3, k4] = a.coefficients;
                let (omega, alpha) = (states[2 * i], states[2 * i + 1]);
                let w2 = omega * omega;
                RotorOutput {
                    thrust_n: efficiency * k1 * w2 * alpha,
                    reaction_torque_nm: efficiency
                        * a.yaw_sign[i]
                        * (k2 * w2 + k3 * w2 * alpha * alpha + k4 * omega * alpha),
                    spin_rad_s: -a.yaw_sign[i] * spin_factor(efficiency) * omega * a.speed_to_rad_s,
                }
            }
        }
    }

    /// The internal state (thrusts, or interleaved speeds and pitches), for recording.
    pub fn state(&self) -> &[f64] {
        match self {
            Actuators::FixedPitch(a) => &a.thrust_n,
            Actuators::VariablePitch(a) => &a.state,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Airframe {
        Airframe::from_columns(
            "q",
            &[0.785, 2.356, 3.927, 5.498],
            &[0.2; 4],
            &[-1.0, 1.0, -1.0, 1.0],
            &[8.0; 4],
            &[0.0; 4],
            &[1.0; 4],
            1.0,
            &[0.01, 0.01, 0.02],
            0.02,
            9.81,
        )
        .unwrap()
    }

    #[test]
    fn lag_is_the_exact_first_order_response() {
        let lag = Lag {
            time_constant_s: 0.025,
            rate_limit_per_s: f64::INFINITY,
        };
        let mut rotors = Actuators::FixedPitch(FixedPitch::new(&quad(), lag, 0.0).unwrap());
        let dt = 1e-3;
        for _ in 0..25 {
            rotors.advance(&[4.0; 4], dt);
        }
        // After one time constant: 4 (1 - e^-1), whatever the step (exact discretisation).
        let expected = 4.0 * (1.0 - (-1.0f64).exp());
        assert!(
            (rotors.state()[0] - expected).abs() < 1e-12,
            "{}",
            rotors.state()[0]
        );
    }

    #[test]
    fn saturation_and_rate_limit() {
        let lag = Lag {
            time_constant_s: 0.0,
            rate_limit_per_s: 50.0,
        };
        let mut rotors = Actuators::FixedPitch(FixedPitch::new(&quad(), lag, 0.0).unwrap());
        rotors.advance(&[100.0, -5.0, 0.01, 3.0], 0.01);
        // 50 N/s over 10 ms: at most 0.5 N of change; the negative command saturates at 0.
        assert_eq!(rotors.state(), &[0.5, 0.0, 0.01, 0.5]);
        for _ in 0..100 {
            rotors.advance(&[100.0, -5.0, 0.01, 3.0], 0.01);
        }
        assert_eq!(rotors.state(), &[8.0, 0.0, 0.01, 3.0]);
    }

    #[test]
    fn health_scales_thrust_torque_and_spin() {
        let mut rotors =
            Actuators::FixedPitch(FixedPitch::new(&quad(), Lag::none(), 1e-5).unwrap());
        rotors.settle(&[4.0; 4]).unwrap();
        let healthy = rotors.output(1, 1.0);
        assert_eq!(healthy.thrust_n, 4.0);
        assert!((healthy.reaction_torque_nm - 0.08).abs() < 1e-15); // ccw: +k_mu f
        assert!((healthy.spin_rad_s + (4.0f64 / 1e-5).sqrt()).abs() < 1e-9);
        let half = rotors.output(1, 0.5);
        assert_eq!(half.thrust_n, 2.0);
        let failed = rotors.output(1, 0.0);
        assert!(
            failed.thrust_n == 0.0 && failed.reaction_torque_nm == 0.0 && failed.spin_rad_s == 0.0
        );
    }

    #[test]
    fn variable_pitch_follows_wang_eq3_and_can_push_down() {
        let k = [2e-8, 1e-9, 3e-10, 1e-6];
        let mut rotors = Actuators::VariablePitch(
            VariablePitch::new(
                &quad(),
                k,
                (0.0, 10_000.0),
                (-0.3, 0.3),
                0.0,
                VariablePitchLags {
                    speed: Lag::none(),
                    pitch: Lag::none(),
                },
            )
            .unwrap(),
        );
        rotors
            .settle(&[9000.0, 0.2, 9000.0, -0.2, 12_000.0, 0.5, 0.0, 0.0])
            .unwrap();
        assert!(rotors
            .settle(&[1.0; 4])
            .unwrap_err()
            .to_string()
            .starts_with("initial_command: expected 8 entries"));
        let (w, a) = (9000.0f64, 0.2f64);
        let out = rotors.output(0, 1.0);
        assert!((out.thrust_n - k[0] * w * w * a).abs() < 1e-12);
        let torque = k[1] * w * w + k[2] * w * w * a * a + k[3] * w * a;
        assert!((out.reaction_torque_nm + torque).abs() < 1e-12); // rotor 1 clockwise
        assert!(rotors.output(1, 1.0).thrust_n < 0.0);
        assert_eq!(&rotors.state()[4..6], &[10_000.0, 0.3]); // saturated
    }

    #[test]
    fn speed_and_pitch_follow_their_own_lag_and_rate_limit() {
        let lags = VariablePitchLags {
            speed: Lag {
                time_constant_s: 0.05,
                rate_limit_per_s: 20_000.0,
            },
            pitch: Lag {
                time_constant_s: 0.01,
                rate_limit_per_s: 1.0,
            },
        };
        let k = [2e-8, 1e-9, 3e-10, 1e-6];
        let mut rotors = Actuators::VariablePitch(
            VariablePitch::new(&quad(), k, (0.0, 10_000.0), (-0.3, 0.3), 0.0, lags).unwrap(),
        );
        rotors
            .settle(&[5000.0, 0.0, 5000.0, 0.0, 5000.0, 0.0, 5000.0, 0.0])
            .unwrap();
        let command = [6000.0, 0.2, 9000.0, -0.2, 5000.0, 0.0, 5000.0, 0.0];
        let t = 0.03;
        let mut many = rotors.clone();
        rotors.advance(&command, t);
        for _ in 0..30 {
            many.advance(&command, t / 30.0);
        }
        // Each channel is its own lag's exact solution (an independent RK4 of its ODE).
        for (k, (&x, &y)) in rotors.state().iter().zip(many.state()).enumerate() {
            let lag = if k % 2 == 0 { lags.speed } else { lags.pitch };
            let start = [5000.0, 0.0][k % 2];
            let reference = integrate_ode(&lag, start, command[k], t);
            let scale = if k % 2 == 0 { 1e4 } else { 1.0 };
            assert!(
                (x - reference).abs() < 1e-9 * scale,
                "channel {k}: {x} vs {reference}"
            );
            assert!(
                (x - y).abs() < 1e-12 * scale,
                "channel {k}: one step {x}, many {y}"
            );
        }
        // The pitch is rate-limited (0.2 / 0.01 = 20 rad/s > 1): 0.03 rad after 30 ms.
        assert!((rotors.state()[1] - 0.03).abs() < 1e-12);
        // The speed is not (1000 / 0.05 = 20,000 per s, at the limit): the exponential.
        let expected = 6000.0 - 1000.0 * (-0.6f64).exp();
        assert!((rotors.state()[0] - expected).abs() < 1e-9);
        assert_eq!(rotors.time_constant_s(), 0.01);
        let err = VariablePitch::new(
            &quad(),
            k,
            (0.0, 1.0),
            (-0.5, 0.5),
            0.0,
            VariablePitchLags {
                pitch: Lag {
                    time_constant_s: 0.0,
                    rate_limit_per_s: -1.0,
                },
                ..VariablePitchLags::default()
            },
        )
        .unwrap_err();
        assert!(
            err.to_string()
                .starts_with("actuator.pitch_rate_limit_rad_s"),
            "{err}"
        );
        let d = VariablePitchLags::default();
        assert!((d.speed.time_constant_s - 1.0 / (20.0 * std::f64::consts::PI)).abs() < 1e-15);
        assert_eq!(d.speed, d.pitch);
    }

    #[test]
    fn bad_parameters_are_named() {
        let bad = Lag {
            time_constant_s: -1.0,
            rate_limit_per_s: 1.0,
        };
        let err = FixedPitch::new(&quad(), bad, 0.0).unwrap_err();
        assert!(
            err.to_string().starts_with("actuator.time_constant_s"),
            "{err}"
        );
        let bad = Lag {
            time_constant_s: 0.0,
            rate_limit_per_s: 0.0,
        };
        let err = FixedPitch::new(&quad(), bad, 0.0).unwrap_err();
        assert!(
            err.to_string().starts_with("actuator.rate_limit_n_s"),
            "{err}"
        );
        let err = VariablePitch::new(
            &quad(),
            [1.0; 4],
            (0.0, 1.0),
            (0.5, -0.5),
            0.0,
            VariablePitchLags {
                speed: Lag::none(),
                pitch: Lag::none(),
            },
        )
        .unwrap_err();
        assert!(
            err.to_string().starts_with("actuator.pitch_bounds"),
            "{err}"
        );
    }

    /// RK4 on `a' = clamp((target - a) / tau, -rate, rate)` with tiny steps.
    fn integrate_ode(lag: &Lag, mut a: f64, target: f64, t: f64) -> f64 {
        let f = |a: f64| {
            ((target - a) / lag.time_constant_s).clamp(-lag.rate_limit_per_s, lag.rate_limit_per_s)
        };
        let n = 200_000;
        let h = t / n as f64;
        for _ in 0..n {
            let k1 = f(a);
            let k2 = f(a + 0.5 * h * k1);
            let k3 = f(a + 0.5 * h * k2);
            let k4 = f(a + h * k3);
            a += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
        a
    }

    #[test]
    fn rate_limited_lag_is_the_exact_solution_of_its_ode() {
        let lag = Lag {
            time_constant_s: 0.05,
            rate_limit_per_s: 50.0,
        };
        // A 6 N step is rate-limited (6 / 0.05 = 120 N/s > 50) until the gap is 2.5 N, at 70 ms.
        for (a0, target, t) in [
            (0.0, 6.0, 0.03),
            (0.0, 6.0, 0.2),
            (6.0, 1.0, 0.15),
            (2.0, 3.0, 0.1),
        ] {
            let exact = lag.response(a0, target, t);
            let reference = integrate_ode(&lag, a0, target, t);
            assert!(
                (exact - reference).abs() < 1e-9,
                "{a0} -> {target} at {t}: {exact} vs {reference}"
            );
        }
        // Exact, so one long step equals many short ones (the old clip-after-lag did not).
        let mut one = Actuators::FixedPitch(FixedPitch::new(&quad(), lag, 0.0).unwrap());
        let mut many = one.clone();
        one.advance(&[8.0, 0.0, 5.0, 1.0], 0.2);
        for _ in 0..50 {
            many.advance(&[8.0, 0.0, 5.0, 1.0], 0.004);
        }
        for (a, b) in one.state().iter().zip(many.state()) {
            assert!(
                (a - b).abs() < 1e-12,
                "{:?} vs {:?}",
                one.state(),
                many.state()
            );
        }
        // `response` does not move the actuator; the instant model jumps at once.
        let mut out = [0.0; 4];
        one.response(&[0.0; 4], 0.0, &mut out);
        assert_eq!(&out, one.state());
        let instant = Actuators::FixedPitch(FixedPitch::new(&quad(), Lag::none(), 0.0).unwrap());
        instant.response(&[1.0, 2.0, 3.0, 4.0], 0.0, &mut out);
        assert_eq!(out, [1.0, 2.0, 3.0, 4.0]);
        assert!(instant.is_instant() && !one.is_instant());
    }

    #[test]
    fn health_scales_spin_by_its_square_root_in_both_models() {
        // One rule: a rotor at efficiency 0.25 turns at half speed (thrust and torque x 0.25).
        let mut fixed = Actuators::FixedPitch(FixedPitch::new(&quad(), Lag::none(), 1e-5).unwrap());
        fixed.settle(&[4.0; 4]).unwrap();
        let k = [2e-8, 1e-9, 3e-10, 1e-6];
        let mut variable = Actuators::VariablePitch(
            VariablePitch::new(
                &quad(),
                k,
                (0.0, 10_000.0),
                (-0.3, 0.3),
                0.1,
                VariablePitchLags {
                    speed: Lag::none(),
                    pitch: Lag::none(),
                },
            )
            .unwrap(),
        );
        variable.settle(&[[9000.0, 0.2]; 4].concat()).unwrap();
        for rotors in [&fixed, &variable] {
            let (healthy, weak) = (rotors.output(0, 1.0), rotors.output(0, 0.25));
            assert!(healthy.spin_rad_s.abs() > 0.0);
            assert!(
                (weak.spin_rad_s - 0.5 * healthy.spin_rad_s).abs()
                    < 1e-12 * healthy.spin_rad_s.abs()
            );
            assert!((weak.thrust_n - 0.25 * healthy.thrust_n).abs() < 1e-12);
            assert_eq!(rotors.output(0, 0.0).spin_rad_s, 0.0);
        }
        assert_eq!(spin_factor(0.25), 0.5);
    }
}
