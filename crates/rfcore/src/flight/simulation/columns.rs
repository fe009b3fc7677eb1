//! A batch recorded into columns: one contiguous buffer per signal for the whole batch, filled
//! by the runs as they finish ([`simulate_batch_columns`]), instead of one [`Trajectory`] per run.
//!
//! Layout: run `i` owns a slot of `grid_rows + 1` rows in every buffer (row-major, `width`
//! values a row). Slot row `j < grid_rows` holds the run's row at the recording grid's `j`-th
//! time ([`SimulationConfig::record_times`]), NaN after the run's last grid row; the last slot
//! row holds a divergence row whose located time is not a grid time (else NaN). So the slots'
//! first `grid_rows` rows are the batch stacked on one time axis, and a run's own trajectory is
//! its first [`RunRecord::grid_rows`] rows plus, when [`RunRecord::off_grid_row`], the last one:
//! exactly the rows [`simulate_batch`](super::simulate_batch) returns for it. Each thread holds
//! one run's [`Trajectory`] at a time (moved into its slot and dropped), so the batch costs its
//! columns and nothing per run. Storage is `f64` or `f32` ([`Sample`]): an `f32` column holds
//! each `f64` value rounded to nearest.

use rayon::prelude::*;

use crate::cancel::Cancel;
use crate::error::{Result, RfError};
use crate::flight::actuator::Actuators;
use crate::flight::simulation::config::SimulationConfig;
use crate::flight::simulation::divergence::Divergence;
use crate::flight::simulation::batch_lanes::{plan, BatchLanes};
use crate::flight::simulation::driver::{check_batch, BatchRun};
use crate::flight::simulation::recording::{SensingRecord, Trajectory};
use crate::flight::vehicle::Vehicle;
use crate::state::{state_vector, STATE_DIM};
use crate::flight::estimation::ERROR_DIM;

/// A value a column stores: `f64`, or `f32` (half the memory; rounded to nearest).
pub trait Sample: Copy + Send + Sync + 'static {
    const NAN: Self;
    fn from_f64(value: f64) -> Self;
}

impl Sample for f64 {
    const NAN: Self = f64::NAN;
    #[inline]
    fn from_f64(value: f64) -> Self {
        value
    }
}

impl Sample for f32 {
    const NAN: Self = f32::NAN;
    #[inline]
    fn from_f64(value: f64) -> Self {
        value as f32
    }
}

/// One signal of the batch: `runs x (grid_rows + 1) x width` values (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Column<T> {
    pub width: usize,
    pub values: Vec<T>,
}

impl<T: Sample> Column<T> {
    fn new(runs: usize, slot_rows: usize, width: usize) -> Self {
        Column {
            width,
            values: vec![T::NAN; runs * slot_rows * width],
        }
    }
}

/// What a run recorded besides its rows: how many of them sit on the grid, whether it has an
/// off-grid divergence row, its divergence and its sensing counts (`rows` moved out, empty).
#[derive(Debug, Clone, PartialEq)]
pub struct RunRecord {
    pub grid_rows: usize,
    pub off_grid_row: bool,
    pub divergence: Option<Divergence>,
    pub sensing: Option<SensingRecord>,
    /// What the run flew on ([`Trajectory::sensed`]).
    pub sensed: &'static str,
}

/// The batch's columns (the truth always; `recorded_measurements` with sensor noise, the `estimate_*`
/// columns and the saturation flags with sensing, else empty) and one [`RunRecord`] per run.
#[derive(Debug, Clone, PartialEq)]
pub struct BatchColumns<T> {
    pub runs: usize,
    /// Rows of the recording grid (`record_times().len()`); each slot has one more.
    pub grid_rows: usize,
    pub position_m: Column<T>,
    pub velocity_m_s: Column<T>,
    /// w, x, y, z.
    pub quaternion: Column<T>,
    /// Z-Y-X roll, pitch, yaw.
    pub euler_rad: Column<T>,
    pub omega_rad_s: Column<T>,
    pub primary_axis: Column<T>,
    /// The commands (N per rotor for fixed pitch; speed and pitch interleaved for variable pitch).
    pub rotor_command: Column<T>,
    /// The rotors' produced thrusts, N.
    pub rotor_thrust_n: Column<T>,
    pub efficiency: Column<T>,
    /// The 12-element measured state vector (with sensor noise; width 0 without).
    pub recorded_measurements: Column<T>,
    /// The estimate packed (position, velocity, quaternion w x y z, body rates; width 13).
    pub estimate_packed: Column<T>,
    /// The estimate's Z-Y-X Euler angles (width 3).
    pub estimate_euler_rad: Column<T>,
    /// One sigma of the estimator's error state (width 15).
    pub estimate_std: Column<T>,
    pub gyro_saturated: Vec<bool>,
    pub accel_saturated: Vec<bool>,
    pub records: Vec<RunRecord>,
}

/// One run's slot in every column.
struct Slot<'a, T> {
    position_m: &'a mut [T],
    velocity_m_s: &'a mut [T],
    quaternion: &'a mut [T],
    euler_rad: &'a mut [T],
    omega_rad_s: &'a mut [T],
    primary_axis: &'a mut [T],
    rotor_command: &'a mut [T],
    rotor_thrust_n: &'a mut [T],
    efficiency: &'a mut [T],
    recorded_measurements: &'a mut [T],
    estimate_packed: &'a mut [T],
    estimate_euler_rad: &'a mut [T],
    estimate_std: &'a mut [T],
    gyro_saturated: &'a mut [bool],
    accel_saturated: &'a mut [bool],
}

/// Splits `values` into `runs` slots of `slot_len` values (an empty column: empty slots).
fn slots<T>(values: &mut [T], runs: usize, slot_len: usize) -> Vec<&mut [T]> {
    if slot_len == 0 {
        return (0..runs).map(|_| <&mut [T]>::default()).collect();
    }
    values.chunks_mut(slot_len).collect()
}

#[inline]
fn put<T: Sample, const N: usize>(slot: &mut [T], width: usize, row: usize, values: [f64; N]) {
    for (dst, v) in slot[row * width..(row + 1) * width].iter_mut().zip(values) {
        *dst = T::from_f64(v);
    }
}

#[inline]
fn put_slice<T: Sample>(slot: &mut [T], width: usize, row: usize, values: &[f64]) {
    for (dst, &v) in slot[row * width..(row + 1) * width].iter_mut().zip(values) {
        *dst = T::from_f64(v);
    }
}

/// Moves `run`'s rows into `slot` (grid rows in place, an off-grid divergence row last) and
/// returns what is left of it.
fn fill<T: Sample>(
    mut run: Trajectory,
    slot: &mut Slot<'_, T>,
    grid: &[f64],
    widths: (usize, usize),
) -> Result<RunRecord> {
    let (count, m) = widths;
    let rows = run.t_s.len();
    // The last row sits on the grid only when its time is the next grid time; a divergence
    // located between two grid times goes to the slot's extra row.
    let mut on_grid = rows;
    if rows > 0 && !(rows <= grid.len() && run.t_s[rows - 1] == grid[rows - 1]) {
        on_grid -= 1;
    }
    if run.t_s[..on_grid] != grid[..on_grid] {
        return Err(RfError::invalid(
            "record_every",
            "internal: a run's recorded times left the recording grid",
        ));
    }
    let sensing_rows = run.sensing.as_mut().map(|s| std::mem::take(&mut s.rows));
    for j in 0..rows {
        let at = if j < on_grid { j } else { grid.len() };
        let s = &run.states[j];
        put(slot.position_m, 3, at, s.position_m.into());
        put(slot.velocity_m_s, 3, at, s.velocity_m_s.into());
        let q = s.attitude.quaternion();
        put(slot.quaternion, 4, at, [q.w, q.i, q.j, q.k]);
        put(slot.euler_rad, 3, at, s.euler_rad());
        put(slot.omega_rad_s, 3, at, s.omega_rad_s.into());
        put(slot.primary_axis, 3, at, s.primary_axis().into());
        put_slice(slot.rotor_command, count, at, &run.rotor_command[j * count..(j + 1) * count]);
        put_slice(slot.rotor_thrust_n, m, at, &run.rotor_thrust_n[j * m..(j + 1) * m]);
        put_slice(slot.efficiency, m, at, &run.efficiency[j * m..(j + 1) * m]);
        if !run.recorded_measurements.is_empty() {
            put_slice(slot.recorded_measurements, STATE_DIM, at, &run.recorded_measurements[j * STATE_DIM..(j + 1) * STATE_DIM]);
        }
        if let Some(row) = sensing_rows.as_ref().and_then(|r| r.get(j)) {
            put(slot.estimate_packed, 13, at, row.state.to_packed());
            let v = state_vector(&row.state);
            put(slot.estimate_euler_rad, 3, at, [v[6], v[7], v[8]]);
            put(slot.estimate_std, ERROR_DIM, at, row.std);
            slot.gyro_saturated[at] = row.gyro_saturated;
            slot.accel_saturated[at] = row.accel_saturated;
        }
    }
    Ok(RunRecord {
        grid_rows: on_grid,
        off_grid_row: on_grid < rows,
        divergence: run.divergence,
        sensed: run.sensed(),
        sensing: run.sensing,
    })
}

/// [`simulate_batch_lanes`](super::simulate_batch_lanes) recorded into columns of `T` (see the
/// module docs): the same runs, seeds and rows, without a [`Trajectory`] per run.
pub fn simulate_batch_columns<T: Sample>(
    vehicle: &Vehicle,
    actuators: &Actuators,
    initial_efficiency: &[f64],
    runs: Vec<BatchRun>,
    config: &SimulationConfig,
    cancel: &Cancel,
    lanes: BatchLanes,
) -> Result<BatchColumns<T>> {
    check_batch(config, &runs)?;
    let n = runs.len();
    let m = vehicle.rotor_count();
    let count = actuators.channels() * m;
    let grid = config.record_times();
    let slot_rows = grid.len() + 1;
    let noise = if config.noise.is_some() { STATE_DIM } else { 0 };
    let sensed = config.sensing.is_some();
    let (packed, euler, std) = if sensed { (13, 3, ERROR_DIM) } else { (0, 0, 0) };
    let flags = if sensed { slot_rows } else { 0 };
    let mut out = BatchColumns {
        runs: n,
        grid_rows: grid.len(),
        position_m: Column::new(n, slot_rows, 3),
        velocity_m_s: Column::new(n, slot_rows, 3),
        quaternion: Column::new(n, slot_rows, 4),
        euler_rad: Column::new(n, slot_rows, 3),
        omega_rad_s: Column::new(n, slot_rows, 3),
        primary_axis: Column::new(n, slot_rows, 3),
        rotor_command: Column::new(n, slot_rows, count),
        rotor_thrust_n: Column::new(n, slot_rows, m),
        efficiency: Column::new(n, slot_rows, m),
        recorded_measurements: Column::new(n, slot_rows, noise),
        estimate_packed: Column::new(n, slot_rows, packed),
        estimate_euler_rad: Column::new(n, slot_rows, euler),
        estimate_std: Column::new(n, slot_rows, std),
        gyro_saturated: vec![false; n * flags],
        accel_saturated: vec![false; n * flags],
        records: Vec::with_capacity(n),
    };
    let w = |c: &Column<T>| slot_rows * c.width;
    let lens = [
        w(&out.position_m), w(&out.velocity_m_s), w(&out.quaternion), w(&out.euler_rad),
        w(&out.omega_rad_s), w(&out.primary_axis), w(&out.rotor_command), w(&out.rotor_thrust_n),
        w(&out.efficiency), w(&out.recorded_measurements), w(&out.estimate_packed),
        w(&out.estimate_euler_rad), w(&out.estimate_std),
    ];
    let mut position = slots(&mut out.position_m.values, n, lens[0]).into_iter();
    let mut velocity = slots(&mut out.velocity_m_s.values, n, lens[1]).into_iter();
    let mut quaternion = slots(&mut out.quaternion.values, n, lens[2]).into_iter();
    let mut euler_rad = slots(&mut out.euler_rad.values, n, lens[3]).into_iter();
    let mut omega = slots(&mut out.omega_rad_s.values, n, lens[4]).into_iter();
    let mut axis = slots(&mut out.primary_axis.values, n, lens[5]).into_iter();
    let mut command = slots(&mut out.rotor_command.values, n, lens[6]).into_iter();
    let mut thrust = slots(&mut out.rotor_thrust_n.values, n, lens[7]).into_iter();
    let mut efficiency = slots(&mut out.efficiency.values, n, lens[8]).into_iter();
    let mut measured = slots(&mut out.recorded_measurements.values, n, lens[9]).into_iter();
    let mut est_packed = slots(&mut out.estimate_packed.values, n, lens[10]).into_iter();
    let mut est_euler = slots(&mut out.estimate_euler_rad.values, n, lens[11]).into_iter();
    let mut est_std = slots(&mut out.estimate_std.values, n, lens[12]).into_iter();
    let mut gyro = slots(&mut out.gyro_saturated, n, flags).into_iter();
    let mut accel = slots(&mut out.accel_saturated, n, flags).into_iter();
    let mut run_slots = Vec::with_capacity(n);
    for _ in 0..n {
        // Every column has exactly `n` slots (or `n` empty ones), so each `next` is `Some`.
        let (Some(position_m), Some(velocity_m_s), Some(quaternion), Some(euler_rad), Some(omega_rad_s)) =
            (position.next(), velocity.next(), quaternion.next(), euler_rad.next(), omega.next())
        else {
            return Err(RfError::invalid("runs", "internal: a column has too few slots"));
        };
        let (Some(primary_axis), Some(rotor_command), Some(rotor_thrust_n), Some(efficiency), Some(recorded_measurements)) =
            (axis.next(), command.next(), thrust.next(), efficiency.next(), measured.next())
        else {
            return Err(RfError::invalid("runs", "internal: a column has too few slots"));
        };
        let (Some(estimate_packed), Some(estimate_euler_rad), Some(estimate_std), Some(gyro_saturated), Some(accel_saturated)) =
            (est_packed.next(), est_euler.next(), est_std.next(), gyro.next(), accel.next())
        else {
            return Err(RfError::invalid("runs", "internal: a column has too few slots"));
        };
        run_slots.push(Slot {
            position_m, velocity_m_s, quaternion, euler_rad, omega_rad_s, primary_axis, rotor_command,
            rotor_thrust_n, efficiency, recorded_measurements, estimate_packed, estimate_euler_rad, estimate_std,
            gyro_saturated, accel_saturated,
        });
    }
    // Each plan (one run, or a group of four in SIMD lanes) takes its runs' slots.
    let plans = plan(vehicle, actuators, initial_efficiency, runs, config, lanes);
    let mut run_slots: Vec<Option<Slot<'_, T>>> = run_slots.into_iter().map(Some).collect();
    let mut work = Vec::with_capacity(plans.len());
    for plan in plans {
        let mut slots = Vec::new();
        for i in plan.indices() {
            let Some(slot) = run_slots.get_mut(i).and_then(Option::take) else {
                return Err(RfError::invalid("runs", "internal: a run's slot was taken twice"));
            };
            slots.push(slot);
        }
        work.push((plan, slots));
    }
    let flown = work
        .into_par_iter()
        .map(|(plan, slots)| {
            let trajectories = plan.fly(
                vehicle,
                actuators,
                initial_efficiency,
                config,
                cancel,
                lanes,
            )?;
            trajectories
                .into_iter()
                .zip(slots)
                .map(|((i, trajectory), mut slot)| Ok((i, fill(trajectory, &mut slot, &grid, (count, m))?)))
                .collect::<Result<Vec<_>>>()
        })
        .collect::<Result<Vec<_>>>()?;
    let mut records: Vec<Option<RunRecord>> = (0..n).map(|_| None).collect();
    for (i, record) in flown.into_iter().flatten() {
        records[i] = Some(record);
    }
    out.records = records.into_iter().flatten().collect();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;
    use crate::control::ZeroCommand;
    use crate::flight::actuator::{FixedPitch, Lag};
    use crate::flight::simulation::simulate_batch;
    use crate::flight::vehicle::Drag;
    use crate::state::RigidBodyState;

    fn runs() -> Vec<BatchRun> {
        // Falling from 1 m and 50 m: the first crashes between two grid times of record_every 7.
        [1.0, 50.0]
            .iter()
            .map(|&h| BatchRun {
                controller: Box::new(ZeroCommand { count: 4 }),
                initial_command: None,
                x0: RigidBodyState { position_m: Vector3::new(0.0, 0.0, -h), ..RigidBodyState::at_rest() },
                faults: vec![],
            })
            .collect()
    }

    #[test]
    fn columns_hold_the_per_run_rows_and_f32_rounds_them() {
        let airframe = crate::fixtures::preset("quad-x");
        let vehicle = Vehicle::new(&airframe, Drag::default()).unwrap();
        let actuators = Actuators::FixedPitch(FixedPitch::new(&airframe, Lag::none(), 0.0).unwrap());
        let mut config = SimulationConfig::new(0.0025, 2, 0.6);
        config.record_every = 7;
        let never = Cancel::never();
        let per_run = simulate_batch(&vehicle, &actuators, &[1.0; 4], runs(), &config, &never).unwrap();
        let wide = simulate_batch_columns::<f64>(&vehicle, &actuators, &[1.0; 4], runs(), &config, &never, BatchLanes::Auto).unwrap();
        let narrow = simulate_batch_columns::<f32>(&vehicle, &actuators, &[1.0; 4], runs(), &config, &never, BatchLanes::Auto).unwrap();
        let slot = wide.grid_rows + 1;
        assert!(wide.records[0].off_grid_row);
        assert_eq!(wide.records[1].grid_rows, wide.grid_rows);
        for (i, run) in per_run.iter().enumerate() {
            let record = &wide.records[i];
            assert_eq!(record.divergence, run.divergence);
            for (j, state) in run.states.iter().enumerate() {
                let at = if j < record.grid_rows { j } else { wide.grid_rows };
                let row = |c: &Column<f64>| c.values[(i * slot + at) * c.width..(i * slot + at + 1) * c.width].to_vec();
                assert_eq!(row(&wide.position_m), state.position_m.as_slice());
                assert_eq!(row(&wide.omega_rad_s), state.omega_rad_s.as_slice());
                assert_eq!(row(&wide.efficiency), &run.efficiency[j * 4..(j + 1) * 4]);
            }
        }
        for (a, b) in narrow.position_m.values.iter().zip(&wide.position_m.values) {
            assert!(a.to_bits() == (*b as f32).to_bits() || (a.is_nan() && b.is_nan()));
        }
    }
}
