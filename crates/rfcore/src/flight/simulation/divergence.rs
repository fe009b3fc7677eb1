//! Divergence: the limits past which a run is declared diverged ([`DivergenceLimits`]), why a run
//! ended early ([`DivergenceKind`], [`Divergence`]; contact with the ground is one of them,
//! [`DivergenceKind::Crashed`], with its [`Impact`]), and how a crossing is found: the cheap
//! check after every RK4 substep and the bisection that locates the crossing within it (`Limits`).

use crate::state::RigidBodyState;

/// Largest `h max(|omega|, 1 / time_constant)` a run accepts (module docs of [`crate::flight::simulation`], "Step size").
pub const MAX_RATE_STEP: f64 = 0.25;

/// Limits past which a run is declared diverged, checked after every RK4 substep; a crossing
/// is located within its substep (the event's time and state are at the crossing).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DivergenceLimits {
    /// Largest angle between body z and world z (down), rad.
    pub max_tilt_rad: f64,
    /// Largest drop below the starting altitude, m.
    pub max_altitude_loss_m: f64,
    /// Largest speed, m/s.
    pub max_speed_m_s: f64,
    /// Largest body rate magnitude, rad/s.
    pub max_rate_rad_s: f64,
}

impl Default for DivergenceLimits {
    fn default() -> Self {
        DivergenceLimits {
            max_tilt_rad: std::f64::consts::FRAC_PI_2,
            max_altitude_loss_m: 100.0,
            max_speed_m_s: 100.0,
            max_rate_rad_s: 200.0,
        }
    }
}

/// Why a run ended early.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DivergenceKind {
    /// The centre of mass reached the ground plane ([`crate::flight::simulation::SimulationConfig::ground_z_m`]).
    Crashed,
    NonFinite,
    /// The controller produced a non-finite command.
    NonFiniteCommand,
    Tilt,
    AltitudeLoss,
    Speed,
    BodyRate,
    /// `h |omega|` grew past [`MAX_RATE_STEP`]: the integrator can no longer resolve the motion
    /// (a numerical failure, not the vehicle's); use more substeps.
    StepSize,
}

impl DivergenceKind {
    /// Every kind, in declaration order (what [`DivergenceKind::from_name`] accepts).
    pub const ALL: [DivergenceKind; 8] = [
        DivergenceKind::Crashed,
        DivergenceKind::NonFinite,
        DivergenceKind::NonFiniteCommand,
        DivergenceKind::Tilt,
        DivergenceKind::AltitudeLoss,
        DivergenceKind::Speed,
        DivergenceKind::BodyRate,
        DivergenceKind::StepSize,
    ];

    /// The kind whose [`DivergenceKind::name`] is `name`.
    pub fn from_name(name: &str) -> Option<DivergenceKind> {
        Self::ALL.into_iter().find(|r| r.name() == name)
    }

    /// A short identifier (`"tilt"`, `"non-finite-command"`, ...).
    pub fn name(self) -> &'static str {
        match self {
            DivergenceKind::Crashed => "crashed",
            DivergenceKind::NonFinite => "non-finite-state",
            DivergenceKind::NonFiniteCommand => "non-finite-command",
            DivergenceKind::Tilt => "tilt",
            DivergenceKind::AltitudeLoss => "altitude-loss",
            DivergenceKind::Speed => "speed",
            DivergenceKind::BodyRate => "body-rate",
            DivergenceKind::StepSize => "step-size",
        }
    }

    pub fn describe(self) -> &'static str {
        match self {
            DivergenceKind::Crashed => "hit the ground",
            DivergenceKind::NonFinite => "state became non-finite",
            DivergenceKind::NonFiniteCommand => "the controller produced a non-finite command",
            DivergenceKind::Tilt => "tilt beyond the limit",
            DivergenceKind::AltitudeLoss => "altitude loss beyond the limit",
            DivergenceKind::Speed => "speed beyond the limit",
            DivergenceKind::BodyRate => "body rate beyond the limit",
            DivergenceKind::StepSize => {
                "body rate too fast for the RK4 substep (numerical): use more substeps"
            }
        }
    }
}

/// A run that ended early: when (the limit crossing, located within the substep), why, and the
/// state at that moment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Divergence {
    pub time_s: f64,
    pub kind: DivergenceKind,
    pub state: RigidBodyState,
}

/// How a crashed run hit the ground, from the state at the located contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impact {
    /// Speed at contact, m/s.
    pub speed_m_s: f64,
    /// Speed into the ground (world NED down), m/s.
    pub vertical_speed_m_s: f64,
    /// Angle between body z and world z (down) at contact, rad (the whole attitude is the
    /// state's).
    pub tilt_rad: f64,
}

impl Divergence {
    /// The impact of a [`DivergenceKind::Crashed`] run (`None` for any other kind).
    pub fn impact(&self) -> Option<Impact> {
        (self.kind == DivergenceKind::Crashed).then(|| Impact {
            speed_m_s: self.state.velocity_m_s.norm(),
            vertical_speed_m_s: self.state.velocity_m_s.z,
            tilt_rad: self.state.primary_axis().z.clamp(-1.0, 1.0).acos(),
        })
    }
}

/// The divergence limits in the form checked after every substep (cheap comparisons; the
/// step-size bound folded into the body-rate limit) and the exceedances a crossing is located on.
pub(crate) struct Limits {
    limits: DivergenceLimits,
    start_altitude_m: f64,
    /// The ground plane's z (NED; infinity: no ground).
    ground_z_m: f64,
    /// `MAX_RATE_STEP / h`: the fastest body rate the substep resolves.
    step_rate_rad_s: f64,
    min_n3z: f64,
    max_speed2: f64,
    max_rate2: f64,
}

impl Limits {
    pub(crate) fn new(
        limits: &DivergenceLimits,
        ground_z_m: Option<f64>,
        start_altitude_m: f64,
        h: f64,
    ) -> Self {
        let step_rate_rad_s = MAX_RATE_STEP / h;
        let max_rate = limits.max_rate_rad_s.min(step_rate_rad_s);
        Limits {
            limits: *limits,
            start_altitude_m,
            ground_z_m: ground_z_m.unwrap_or(f64::INFINITY),
            step_rate_rad_s,
            // tilt > max  <=>  n3z = cos(tilt) < cos(max), for max below pi.
            min_n3z: if limits.max_tilt_rad < std::f64::consts::PI {
                limits.max_tilt_rad.cos()
            } else {
                f64::NEG_INFINITY
            },
            max_speed2: limits.max_speed_m_s * limits.max_speed_m_s,
            max_rate2: max_rate * max_rate,
        }
    }

    /// `true` when the state is finite and within every limit (NaN fails every comparison).
    #[inline]
    pub(crate) fn within(&self, s: &RigidBodyState) -> bool {
        let q = s.attitude.quaternion();
        // n3z, the z component of body z in the world frame.
        let n3z = q.w * q.w - q.i * q.i - q.j * q.j + q.k * q.k;
        self.within_parts(
            n3z,
            s.position_m.into(),
            s.velocity_m_s.norm_squared(),
            s.omega_rad_s.norm_squared(),
        )
    }

    /// [`Limits::within`] from what it compares: `n3z` (`w^2 - x^2 - y^2 + z^2` of the
    /// attitude), the position and the squared norms of velocity and body rate (nalgebra's
    /// `(x^2 + y^2) + z^2`); the SIMD lanes compute these four at once.
    #[inline]
    pub(crate) fn within_parts(&self, n3z: f64, position_m: [f64; 3], speed2: f64, rate2: f64) -> bool {
        n3z >= self.min_n3z
            && position_m[2] <= self.ground_z_m
            && self.start_altitude_m + position_m[2] <= self.limits.max_altitude_loss_m
            && speed2 <= self.max_speed2
            && rate2 <= self.max_rate2
            && position_m[0].is_finite()
            && position_m[1].is_finite()
    }

    /// How far past each limit the state is (positive: beyond), in the order of precedence
    /// (the ground first: a vehicle that hits it crashed, whatever else it did at that instant).
    fn exceedances(&self, s: &RigidBodyState) -> [(DivergenceKind, f64); 6] {
        let l = &self.limits;
        let rate = s.omega_rad_s.norm();
        [
            (DivergenceKind::Crashed, s.position_m.z - self.ground_z_m),
            (
                DivergenceKind::Tilt,
                s.primary_axis().z.clamp(-1.0, 1.0).acos() - l.max_tilt_rad,
            ),
            (
                DivergenceKind::AltitudeLoss,
                self.start_altitude_m + s.position_m.z - l.max_altitude_loss_m,
            ),
            (
                DivergenceKind::Speed,
                s.velocity_m_s.norm() - l.max_speed_m_s,
            ),
            (DivergenceKind::BodyRate, rate - l.max_rate_rad_s),
            (DivergenceKind::StepSize, rate - self.step_rate_rad_s),
        ]
    }

    /// The first limit `s` is beyond, if any.
    pub(crate) fn exceeded(&self, s: &RigidBodyState) -> Option<DivergenceKind> {
        if !s.is_finite() {
            return Some(DivergenceKind::NonFinite);
        }
        self.exceedances(s)
            .into_iter()
            .find(|(_, e)| *e > 0.0)
            .map(|(r, _)| r)
    }

    /// Where within an interval of length `len` a limit is first crossed: `step(l)` integrates
    /// `l` from the interval's start (within the limits) to a state, and the end state is
    /// beyond. Returns the elapsed time and the kind: the smallest bisected crossing over the
    /// limits the end state exceeds (the end itself when it is non-finite).
    pub(crate) fn locate(
        &self,
        len: f64,
        end: &RigidBodyState,
        mut step: impl FnMut(f64) -> RigidBodyState,
    ) -> (f64, DivergenceKind) {
        if !end.is_finite() {
            return (len, DivergenceKind::NonFinite);
        }
        let mut best = (len, DivergenceKind::NonFinite);
        let mut found = false;
        for (i, (kind, excess)) in self.exceedances(end).into_iter().enumerate() {
            if excess <= 0.0 {
                continue;
            }
            // Bisection on [lo, hi] with the limit not exceeded at lo, exceeded at hi: hi is
            // returned, so the reported state is just beyond the limit.
            let (mut lo, mut hi) = (0.0, if found { best.0 } else { len });
            if found {
                // Only a crossing before the current best can win.
                let at = step(hi);
                if !(at.is_finite() && self.exceedances(&at)[i].1 > 0.0) {
                    continue;
                }
            }
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                let at = step(mid);
                if !at.is_finite() || self.exceedances(&at)[i].1 > 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            if !found || hi < best.0 {
                best = (hi, kind);
                found = true;
            }
        }
        best
    }
}
