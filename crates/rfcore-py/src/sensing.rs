//! Bindings for flying on sensors: the `Sensing` settings (`rotorfault.Sensing`: a named sensor
//! suite, its IMU part and rates, the seed), defaults from the core's `Sensing::default()`, values
//! checked by its `check()`. Translation only.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyInt, PyString};

use rfcore::flight::simulation::{ImuPart, Sensing, SuiteName};

use crate::convert::{real, settings_protocol, to_py_err};

/// What the controller flies on with sensors: the sensor suite (`"mocap"`, `"gnss"`, `"rtk"`),
/// the IMU part (`"icm-42688-p"`, `"mpu-6000"`) and its output data rate, the position source's
/// rate (`None`: the suite's), the gyroscope's range in rad/s (`None`: the part's +/-2000 deg/s;
/// a what-if for spins past it), and the seed of the sensors' random streams (run ``i`` of a
/// batch uses ``seed + i``). The estimator is matched to the sensors.
///
/// Examples:
///
///     >>> import rotorfault as rf
///     >>> sensing = rf.Sensing(suite="gnss")
///     >>> sensing.suite, sensing.imu
///     ('gnss', 'icm-42688-p')
#[pyclass(name = "Sensing", module = "rotorfault._rfcore", frozen)]
#[derive(Clone)]
pub struct PySensing {
    pub(crate) inner: Sensing,
}

impl PySensing {
    const FIELDS: &'static [&'static str] = &[
        "suite",
        "imu",
        "imu_rate_hz",
        "position_rate_hz",
        "gyro_range_rad_s",
        "seed",
    ];
}

fn name<'py>(field: &str, value: &Bound<'py, PyAny>) -> PyResult<String> {
    if !value.is_instance_of::<PyString>() {
        return Err(PyTypeError::new_err(format!(
            "{field}: expected a string, got {}",
            value.get_type().name()?
        )));
    }
    value.extract()
}

fn seed(value: &Bound<'_, PyAny>) -> PyResult<u64> {
    if value.is_instance_of::<PyBool>() || !value.is_instance_of::<PyInt>() {
        return Err(PyTypeError::new_err(format!(
            "sensing.seed: expected an integer, got {}",
            value.get_type().name()?
        )));
    }
    value.extract::<u64>().map_err(|_| {
        PyValueError::new_err(format!(
            "sensing.seed: must lie in [0, 2**64), got {}",
            value.repr().map(|r| r.to_string()).unwrap_or_default()
        ))
    })
}

settings_protocol!(PySensing, {
    #[new]
    #[pyo3(signature = (*, suite=None, imu=None, imu_rate_hz=None, position_rate_hz=None, gyro_range_rad_s=None, seed=None))]
    fn new(
        suite: Option<Bound<'_, PyAny>>,
        imu: Option<Bound<'_, PyAny>>,
        imu_rate_hz: Option<Bound<'_, PyAny>>,
        position_rate_hz: Option<Bound<'_, PyAny>>,
        gyro_range_rad_s: Option<Bound<'_, PyAny>>,
        seed: Option<Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let d = Sensing::default();
        let inner = Sensing {
            suite: match suite {
                Some(v) => SuiteName::from_name("sensing.suite", &name("sensing.suite", &v)?)
                    .map_err(to_py_err)?,
                None => d.suite,
            },
            imu: match imu {
                Some(v) => ImuPart::from_name("sensing.imu", &name("sensing.imu", &v)?)
                    .map_err(to_py_err)?,
                None => d.imu,
            },
            imu_rate_hz: match imu_rate_hz {
                Some(v) => real("sensing.imu_rate_hz", &v)?,
                None => d.imu_rate_hz,
            },
            position_rate_hz: match position_rate_hz {
                Some(v) if !v.is_none() => Some(real("sensing.position_rate_hz", &v)?),
                _ => d.position_rate_hz,
            },
            gyro_range_rad_s: match gyro_range_rad_s {
                Some(v) if !v.is_none() => Some(real("sensing.gyro_range_rad_s", &v)?),
                _ => d.gyro_range_rad_s,
            },
            seed: match seed {
                Some(v) => self::seed(&v)?,
                None => d.seed,
            },
        };
        inner.check().map_err(to_py_err)?;
        Ok(PySensing { inner })
    }
    #[getter]
    fn suite(&self) -> &'static str {
        self.inner.suite.name()
    }
    #[getter]
    fn imu(&self) -> &'static str {
        self.inner.imu.name()
    }
    #[getter]
    fn imu_rate_hz(&self) -> f64 {
        self.inner.imu_rate_hz
    }
    #[getter]
    fn position_rate_hz(&self) -> Option<f64> {
        self.inner.position_rate_hz
    }
    #[getter]
    fn gyro_range_rad_s(&self) -> Option<f64> {
        self.inner.gyro_range_rad_s
    }
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.seed
    }
    /// The gyroscope's range in effect, rad/s (the part's when `gyro_range_rad_s` is None).
    #[getter]
    fn gyro_range_in_effect_rad_s(&self) -> f64 {
        self.inner.profile().imu.gyro.range_rad_s
    }
    /// The position source's rate in effect, Hz (the suite's when `position_rate_hz` is None).
    #[getter]
    fn position_rate_in_effect_hz(&self) -> f64 {
        self.inner.profile().position.rate_hz
    }
    /// The names `suite` accepts.
    #[classattr]
    #[pyo3(name = "SUITES")]
    fn suites() -> Vec<&'static str> {
        SuiteName::ALL.iter().map(|s| s.name()).collect()
    }
    /// The names `imu` accepts.
    #[classattr]
    #[pyo3(name = "IMUS")]
    fn imus() -> Vec<&'static str> {
        ImuPart::ALL.iter().map(|s| s.name()).collect()
    }
});
