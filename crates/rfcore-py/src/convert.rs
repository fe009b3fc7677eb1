//! The one conversion layer between Python and the core: core errors to `ValueError` (and a
//! cancelled call to `KeyboardInterrupt`), the GIL helper every heavy call uses (which also
//! watches for Ctrl-C), and array views. Every bindings file uses these; none defines
//! its own.

use std::sync::mpsc::{channel, RecvTimeoutError};
use std::sync::OnceLock;
use std::time::Duration;

use nalgebra::DMatrix;
use numpy::{IntoPyArray, PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::{PyKeyboardInterrupt, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use rfcore::{Cancel, RfError};

pub(crate) fn to_py_err(error: RfError) -> PyErr {
    match error {
        // Only a Ctrl-C cancels (`detached`), so the core's "interrupted" is Python's.
        RfError::Interrupted => PyKeyboardInterrupt::new_err(error.to_string()),
        _ => PyValueError::new_err(error.to_string()),
    }
}

/// How often the calling thread looks for Ctrl-C while a heavy call runs. With the core's checks
/// (about every millisecond of work, `rfcore::cancel`) a call stops within about this long.
pub(crate) const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Stack of rayon's worker threads, where heavy calls run (a Python callable controller too):
/// the main thread's usual 8 MiB rather than Rust's 2 MiB.
const WORKER_STACK_BYTES: usize = 8 << 20;

/// Python's main thread (`threading.main_thread().ident`), recorded when the module loads: the
/// only thread Python delivers Ctrl-C to.
static MAIN_THREAD: OnceLock<u64> = OnceLock::new();

/// The process the module loaded in: a `fork()`ed child inherits no rayon threads, so work is
/// never handed to the pool there (the hand-over would wait forever).
static LOADED_IN: OnceLock<u32> = OnceLock::new();

/// Records Python's main thread and gives rayon's global pool (unless something built it first)
/// the stack a Python callback may need: called once, when the module loads.
pub(crate) fn prepare_threads(py: Python<'_>) -> PyResult<()> {
    let _ = rayon::ThreadPoolBuilder::new()
        .stack_size(WORKER_STACK_BYTES)
        .build_global();
    let ident: u64 = py
        .import("threading")?
        .call_method0("main_thread")?
        .getattr("ident")?
        .extract()?;
    let _ = MAIN_THREAD.set(ident);
    let _ = LOADED_IN.set(std::process::id());
    Ok(())
}

/// Python's main thread, in the process the module loaded in: the one place a signal can arrive
/// and the pool is alive.
fn watchable() -> bool {
    // SAFETY: reads the calling thread's identifier; needs no interpreter state.
    let current = unsafe { pyo3::ffi::PyThread_get_thread_ident() } as u64;
    MAIN_THREAD.get().is_some_and(|&main| main == current)
        && LOADED_IN.get() == Some(&std::process::id())
}

/// Runs `work` with the GIL released and converts core errors: the one helper every heavy call
/// uses. On Python's main thread the work runs on rayon's pool while this thread looks for
/// Ctrl-C every [`SIGNAL_POLL`] (re-attaching briefly: `PyErr_CheckSignals` acts only there); on
/// a signal it cancels the work's [`Cancel`] token, waits for the work to stop (the core checks
/// the token in its loops, rayon batches included) and returns the `KeyboardInterrupt`, whatever
/// the work returned. Handing the work over costs about 10 us. On any other thread (Dask
/// workers, a controller callback) no signal can arrive, so the work runs right here, as it does
/// in a `fork()`ed child (whose rayon pool has no threads).
pub(crate) fn detached<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&Cancel) -> rfcore::Result<T> + Send,
{
    let cancel = Cancel::new();
    if !watchable() {
        return py.detach(|| work(&cancel)).map_err(to_py_err);
    }
    let (result, interrupt) = py.detach(|| watched(work, &cancel));
    match interrupt {
        Some(err) => Err(err),
        None => result.map_err(to_py_err),
    }
}

/// `work` on rayon's pool while this thread polls for signals (see [`detached`]); returns the
/// work's result and the signal's exception, if one came. A panic in the work is re-raised here
/// when the scope ends (pyo3 turns it into `PanicException`).
fn watched<T, F>(work: F, cancel: &Cancel) -> (rfcore::Result<T>, Option<PyErr>)
where
    T: Send,
    F: FnOnce(&Cancel) -> rfcore::Result<T> + Send,
{
    let (done, finished) = channel();
    rayon::in_place_scope(|scope| {
        scope.spawn(move |_| {
            let _ = done.send(work(cancel));
        });
        let mut interrupt = None;
        loop {
            match finished.recv_timeout(SIGNAL_POLL) {
                Ok(result) => return (result, interrupt),
                Err(RecvTimeoutError::Timeout) => {
                    if interrupt.is_none() {
                        if let Err(err) = Python::attach(|py| py.check_signals()) {
                            cancel.cancel();
                            interrupt = Some(err);
                        }
                    }
                }
                // The work panicked (its sender dropped): the scope re-raises the panic.
                Err(RecvTimeoutError::Disconnected) => return (Err(RfError::Interrupted), interrupt),
            }
        }
    })
}

/// Borrows a contiguous 1-D array as a slice, naming the field if it is not contiguous.
pub(crate) fn slice1<'a>(field: &str, array: &'a PyReadonlyArray1<'_, f64>) -> PyResult<&'a [f64]> {
    array
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{field}: must be a contiguous array")))
}

pub(crate) fn slice2<'a>(field: &str, array: &'a PyReadonlyArray2<'_, f64>) -> PyResult<&'a [f64]> {
    array
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{field}: must be a C-contiguous array")))
}

pub(crate) fn read_only<'py>(py: Python<'py>, values: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    let array = values.into_pyarray(py);
    array.readwrite().make_nonwriteable();
    array
}

pub(crate) fn matrix(field: &str, array: &PyReadonlyArray2<'_, f64>) -> PyResult<DMatrix<f64>> {
    let view = array.as_array();
    let (rows, cols) = view.dim();
    let flat: Vec<f64> = view.iter().copied().collect();
    if flat.len() != rows * cols {
        return Err(PyValueError::new_err(format!("{field}: malformed array")));
    }
    Ok(DMatrix::from_row_slice(rows, cols, &flat))
}

// -- settings classes: one protocol for the named settings Python uses directly ----------------

/// 0-based rotor indices as rotor numbers (from 1): wherever a rotor is named, it is numbered from 1.
pub(crate) fn rotor_numbers(indices: &[usize]) -> Vec<usize> {
    indices.iter().map(|k| k + 1).collect()
}

/// Rotor numbers (from 1) as the core's 0-based indices; `field[k]` names a 0.
pub(crate) fn rotor_indices(field: &str, rotors: &[usize]) -> PyResult<Vec<usize>> {
    rotors
        .iter()
        .enumerate()
        .map(|(k, &rotor)| {
            rotor.checked_sub(1).ok_or_else(|| {
                PyValueError::new_err(format!("{field}[{k}]: rotors are numbered from 1, got 0"))
            })
        })
        .collect()
}

/// A real number for field `field`, by Python's rule (`numbers.Real`, not a bool): anything else
/// is a `TypeError` naming the field; the value rules are the core's `check`s.
pub(crate) fn real(field: &str, value: &Bound<'_, PyAny>) -> PyResult<f64> {
    use pyo3::types::PyBool;
    let real_type = value.py().import("numbers")?.getattr("Real")?;
    if value.is_instance_of::<PyBool>() || !value.is_instance(&real_type)? {
        return Err(PyTypeError::new_err(format!(
            "{field}: expected a real number, got {}",
            value.get_type().name()?
        )));
    }
    value.extract::<f64>().map_err(|_| {
        PyValueError::new_err(format!("{field}: must be finite, got a number too large for a float"))
    })
}

/// A count for field `field` (an `int`, not a bool, >= 0): anything else is a `TypeError` or a
/// `ValueError` naming the field, never pyo3's bare overflow of a negative number.
pub(crate) fn count(field: &str, value: &Bound<'_, PyAny>) -> PyResult<usize> {
    use pyo3::types::{PyBool, PyInt};
    if value.is_instance_of::<PyBool>() || !value.is_instance_of::<PyInt>() {
        return Err(PyTypeError::new_err(format!("{field}: expected an int, got {}", value.get_type().name()?)));
    }
    let wide: i128 = value
        .extract()
        .map_err(|_| PyValueError::new_err(format!("{field}: must be a count >= 0 that fits in 64 bits")))?;
    usize::try_from(wide)
        .map_err(|_| PyValueError::new_err(format!("{field}: must be a count in [0, 2**64), got {wide}")))
}

/// The field values of a settings object, by name.
fn field_values<'py>(obj: &Bound<'py, PyAny>, fields: &[&str]) -> PyResult<Vec<Bound<'py, PyAny>>> {
    fields.iter().map(|f| obj.getattr(*f)).collect()
}

/// `Name(field=value, ...)`, as a dataclass prints.
pub(crate) fn settings_repr(obj: &Bound<'_, PyAny>, fields: &[&str]) -> PyResult<String> {
    let parts: PyResult<Vec<String>> = fields
        .iter()
        .map(|f| Ok(format!("{f}={}", obj.getattr(*f)?.repr()?)))
        .collect();
    Ok(format!("{}({})", obj.get_type().name()?, parts?.join(", ")))
}

/// Equal type and equal fields (NaN fields compare unequal, as floats do).
pub(crate) fn settings_eq(a: &Bound<'_, PyAny>, b: &Bound<'_, PyAny>, fields: &[&str]) -> PyResult<bool> {
    if !b.get_type().is(&a.get_type()) {
        return Ok(false);
    }
    for f in fields {
        if !a.getattr(*f)?.eq(b.getattr(*f)?)? {
            return Ok(false);
        }
    }
    Ok(true)
}

/// The hash of the field values (equal settings hash equal; frozen, so usable as keys).
pub(crate) fn settings_hash(obj: &Bound<'_, PyAny>, fields: &[&str]) -> PyResult<isize> {
    PyTuple::new(obj.py(), field_values(obj, fields)?)?.hash()
}

/// Every field as a keyword argument (the constructor takes them back: copies and pickling).
pub(crate) fn settings_kwargs<'py>(obj: &Bound<'py, PyAny>, fields: &[&str]) -> PyResult<Bound<'py, PyDict>> {
    let kwargs = PyDict::new(obj.py());
    for f in fields {
        kwargs.set_item(*f, obj.getattr(*f)?)?;
    }
    Ok(kwargs)
}

/// A copy with some fields changed, validated as a new object is (an unknown field is a
/// `TypeError` naming it and the fields).
pub(crate) fn settings_replace<'py>(
    obj: &Bound<'py, PyAny>,
    fields: &[&str],
    changes: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let kwargs = settings_kwargs(obj, fields)?;
    if let Some(changes) = changes {
        for (key, value) in changes.iter() {
            let name: String = key.extract()?;
            if !fields.contains(&name.as_str()) {
                return Err(PyTypeError::new_err(format!(
                    "{name}: not a field of {} (fields: {})",
                    obj.get_type().name()?,
                    fields.join(", ")
                )));
            }
            kwargs.set_item(name, value)?;
        }
    }
    obj.get_type().call((), Some(&kwargs)).map(|o| o.into_any())
}

/// One settings class used directly from Python: keyword-only, defaults from the core's
/// `Default`, types checked here (`<prefix>.<field>: expected a real number`), values once by the
/// core's `check`; frozen, comparable, hashable, picklable, `replace(**changes)`, `FIELDS`. A
/// field may sit deeper in the core's struct (`mass_kg => model.mass_kg`); `pyclass = subclass` lets a
/// Python class extend it (methods only: the values stay the core's); `methods = { ... }` adds
/// the class's own methods.
macro_rules! settings_class {
    (
        $(#[$doc:meta])* $py:ident, $pyname:literal, $core:ident, $(pyclass = $flag:ident,)? prefix = $prefix:literal, check = $check:expr,
        { $($field:ident => $($core_field:ident).+),+ $(,)? } $(, methods = { $($methods:tt)* })?
    ) => {
        $(#[$doc])*
        #[::pyo3::pyclass(name = $pyname, module = "rotorfault._rfcore", frozen $(, $flag)?)]
        #[derive(Clone)]
        pub struct $py {
            pub(crate) inner: $core,
        }

        impl $py {
            const FIELDS: &'static [&'static str] = &[$(stringify!($field)),+];
        }

        $crate::convert::settings_protocol!($py, {
            #[new]
            #[pyo3(signature = (*, $($field=None),+))]
            fn new($($field: Option<::pyo3::Bound<'_, ::pyo3::PyAny>>),+) -> ::pyo3::PyResult<Self> {
                let mut inner = $core::default();
                $(
                    if let Some(v) = $field {
                        inner.$($core_field).+ = $crate::convert::real(concat!($prefix, ".", stringify!($field)), &v)?;
                    }
                )+
                let check: fn(&$core) -> rfcore::Result<()> = $check;
                check(&inner).map_err($crate::convert::to_py_err)?;
                Ok($py { inner })
            }
            $(
                #[getter]
                fn $field(&self) -> f64 {
                    self.inner.$($core_field).+
                }
            )+
            $($($methods)*)?
        });
    };
}
pub(crate) use settings_class;

/// A value's methods (repr, equality, hash, all over its `FIELDS`) for a class `$py` with a
/// `FIELDS` constant, after its own methods: one `#[pymethods]` block, so that no class writes
/// the three delegations again (`settings_protocol!` adds the settings' copy and pickling).
macro_rules! value_protocol {
    ($py:ident, { $($methods:tt)* }) => {
        #[::pyo3::pymethods]
        impl $py {
            $($methods)*
            fn __repr__(slf: &::pyo3::Bound<'_, Self>) -> ::pyo3::PyResult<String> {
                $crate::convert::settings_repr(::pyo3::Bound::as_any(slf), Self::FIELDS)
            }
            fn __eq__(slf: &::pyo3::Bound<'_, Self>, other: &::pyo3::Bound<'_, ::pyo3::PyAny>) -> ::pyo3::PyResult<bool> {
                $crate::convert::settings_eq(::pyo3::Bound::as_any(slf), other, Self::FIELDS)
            }
            fn __hash__(slf: &::pyo3::Bound<'_, Self>) -> ::pyo3::PyResult<isize> {
                $crate::convert::settings_hash(::pyo3::Bound::as_any(slf), Self::FIELDS)
            }
        }
    };
}
pub(crate) use value_protocol;

/// The keyword protocol's methods (`FIELDS`, and pickling through the keyword-only constructor:
/// `__getnewargs_ex__` gives every field by name) for a class `$py` with a `FIELDS` constant, after
/// its own methods: the one pickling of every class whose constructor takes its fields by
/// keyword. `then = value_protocol` hands the methods on to that macro (one `#[pymethods]` block).
macro_rules! pickle_protocol {
    ($py:ident, { $($methods:tt)* } $(, then = $next:ident)?) => {
        $crate::convert::pickle_protocol!(@emit $py, [$($next)?], {
            $($methods)*
            /// The field names, in order.
            #[classattr]
            #[pyo3(name = "FIELDS")]
            fn fields() -> Vec<&'static str> {
                Self::FIELDS.to_vec()
            }
            fn __getnewargs_ex__<'py>(slf: &::pyo3::Bound<'py, Self>) -> ::pyo3::PyResult<((), ::pyo3::Bound<'py, ::pyo3::types::PyDict>)> {
                Ok(((), $crate::convert::settings_kwargs(::pyo3::Bound::as_any(slf), Self::FIELDS)?))
            }
        });
    };
    (@emit $py:ident, [], { $($methods:tt)* }) => {
        #[::pyo3::pymethods]
        impl $py {
            $($methods)*
        }
    };
    (@emit $py:ident, [$next:ident], { $($methods:tt)* }) => {
        $crate::convert::$next!($py, { $($methods)* });
    };
}
pub(crate) use pickle_protocol;

/// The settings protocol's methods (`replace`, `pickle_protocol!`'s `FIELDS` and pickling, and
/// `value_protocol!`'s repr, equality, hash) for a class `$py` with a `FIELDS` constant, after its
/// own methods (the constructor, the getters): `settings_class!` uses it, and so does a settings
/// class whose constructor is written by hand.
macro_rules! settings_protocol {
    ($py:ident, { $($methods:tt)* }) => {
        $crate::convert::pickle_protocol!($py, {
            $($methods)*
            /// A copy with ``changes`` (validated like a new object).
            #[pyo3(signature = (**changes))]
            fn replace<'py>(slf: &::pyo3::Bound<'py, Self>, changes: Option<&::pyo3::Bound<'py, ::pyo3::types::PyDict>>) -> ::pyo3::PyResult<::pyo3::Bound<'py, ::pyo3::PyAny>> {
                $crate::convert::settings_replace(::pyo3::Bound::as_any(slf), Self::FIELDS, changes)
            }
        }, then = value_protocol);
    };
}
pub(crate) use settings_protocol;

/// `N` real numbers for field `field` (`names` says what they are, e.g. `"w_f, w_p, w_q, w_r"`):
/// a sequence of exactly `N`, each a real number (`<field>[k]: expected a real number`); the value
/// rules are the core's.
pub(crate) fn fixed_reals<const N: usize>(field: &str, names: &str, value: &Bound<'_, PyAny>) -> PyResult<[f64; N]> {
    use pyo3::types::PyString;
    let kind = || value.get_type().name().map(|n| n.to_string()).unwrap_or_default();
    let not_numbers = || PyTypeError::new_err(format!("{field}: expected {N} numbers ({names}), got {}", kind()));
    if value.is_instance_of::<PyString>() {
        return Err(not_numbers());
    }
    let items: Vec<Bound<'_, PyAny>> = value.try_iter().map_err(|_| not_numbers())?.collect::<PyResult<_>>()?;
    if items.len() != N {
        return Err(PyValueError::new_err(format!("{field}: expected {N} entries ({names}), got {}", items.len())));
    }
    let mut out = [0.0; N];
    for (k, item) in items.iter().enumerate() {
        out[k] = real(&format!("{field}[{k}]"), item)?;
    }
    Ok(out)
}

/// Warns (`DeprecationWarning`) that `old` is deprecated in favour of `new`, in the words of
/// `rotorfault._util.deprecation.warn` (removed after one release).
pub(crate) fn deprecated(py: Python<'_>, old: &str, new: &str) -> PyResult<()> {
    let message = format!("{old} is deprecated and will be removed in the next release; use {new}");
    let message = std::ffi::CString::new(message).map_err(|e| PyValueError::new_err(e.to_string()))?;
    PyErr::warn(py, &py.get_type::<pyo3::exceptions::PyDeprecationWarning>(), &message, 1)
}

/// The positional form of a class that was a Python dataclass (its fields in `fields` order),
/// kept for one release: each positional value fills its field in `given` (the keywords), with
/// a `DeprecationWarning` naming the keyword form; a field given both ways is a `TypeError`.
pub(crate) fn deprecated_positional<'py>(
    class: &str,
    fields: &[&str],
    args: &Bound<'py, PyTuple>,
    given: &mut [Option<Bound<'py, PyAny>>],
) -> PyResult<()> {
    if args.is_empty() {
        return Ok(());
    }
    if args.len() > fields.len() {
        return Err(PyTypeError::new_err(format!(
            "{class}: takes at most {} positional arguments (deprecated; give keywords: {}), got {}",
            fields.len(),
            fields.join(", "),
            args.len()
        )));
    }
    let py = args.py();
    let message = format!(
        "{class}(positional arguments) is deprecated and will be removed in the next release; use {class}({}=...)",
        fields[..args.len()].join("=..., ")
    );
    let message = std::ffi::CString::new(message).map_err(|e| PyValueError::new_err(e.to_string()))?;
    PyErr::warn(py, &py.get_type::<pyo3::exceptions::PyDeprecationWarning>(), &message, 2)?;
    for (k, value) in args.iter().enumerate() {
        if given[k].is_some() {
            return Err(PyTypeError::new_err(format!("{class}: {} given by position and by keyword", fields[k])));
        }
        given[k] = Some(value);
    }
    Ok(())
}

/// `cell`'s object, made by `make` on the first read and kept. Made outside the lock: making a
/// Python object can run the garbage collector and release the GIL, and a second thread waiting
/// on the lock while holding the GIL would deadlock (pyo3's warning about `OnceLock`).
pub fn kept<'py, T>(
    py: Python<'py>,
    cell: &OnceLock<Py<T>>,
    make: impl FnOnce() -> PyResult<Bound<'py, T>>,
) -> PyResult<Bound<'py, T>> {
    if let Some(object) = cell.get() {
        return Ok(object.bind(py).clone());
    }
    let object = make()?.unbind();
    Ok(cell.get_or_init(|| object).bind(py).clone())
}
