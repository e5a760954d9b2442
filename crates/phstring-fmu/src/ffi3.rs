//! The FMI 3.0 Co-Simulation C interface over the same [`Instance`] as FMI 2.0 (`ffi`):
//! every function of `fmi3Functions.h` is exported; those of Model Exchange, Scheduled
//! Execution, event mode, clocks and variable types other than `Float64` refuse with
//! `fmi3Error` (or succeed for zero variables), since the FMU declares none of them.

use std::ffi::{c_char, c_int, c_void};
use std::panic::catch_unwind;
use std::path::PathBuf;

use crate::error::FmuError;
use crate::ffi::{
    c_string, deserialize_state, free_state, get_state, no_such, serialize_state, set_state, slice,
    slice_mut, state_size, str_arg, with,
};
use crate::handles;
use crate::instance::{Api, Instance, Logger, Mode, Status};

/// `fmi3Status`.
pub type Fmi3Status = c_int;
/// `fmi3Instance`.
pub type Fmi3Instance = *mut c_void;
/// `fmi3FMUState`.
pub type Fmi3FmuState = *mut c_void;
/// `fmi3LogMessageCallback`.
pub type Fmi3LogMessage = Option<
    unsafe extern "C" fn(
        env: *mut c_void,
        status: c_int,
        category: *const c_char,
        message: *const c_char,
    ),
>;

/// The master's logger with its environment.
struct CLog3 {
    f: unsafe extern "C" fn(*mut c_void, c_int, *const c_char, *const c_char),
    env: *mut c_void,
}

// SAFETY: the FMI standard lets an instance be called from any thread (one call at a time);
// the environment pointer is the master's and only passed back to it.
unsafe impl Send for CLog3 {}

impl CLog3 {
    fn log(&self, status: Status, category: &str, message: &str) {
        let (c, m) = (c_string(category), c_string(message));
        // SAFETY: the master's callback with valid NUL-terminated strings (FMI 3.0 passes
        // the message as it is, not as a format).
        unsafe { (self.f)(self.env, status as c_int, c.as_ptr(), m.as_ptr()) };
    }
}

/// `fmi3GetVersion`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

/// `fmi3InstantiateCoSimulation`: reads `scenario.toml` in `resourcePath` and checks the
/// instantiation token. Event mode and early return are not supported. Null on failure,
/// with the reason logged.
///
/// # Safety
/// The pointers follow the FMI 3.0 contract.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instance_name: *const c_char,
    token: *const c_char,
    resource_path: *const c_char,
    _visible: bool,
    logging_on: bool,
    event_mode_used: bool,
    _early_return_allowed: bool,
    _required_intermediate: *const u32,
    _n_required_intermediate: usize,
    env: *mut c_void,
    log_message: Fmi3LogMessage,
    _intermediate_update: *const c_void,
) -> Fmi3Instance {
    let result = catch_unwind(|| {
        // SAFETY: FMI contract.
        let name = unsafe { str_arg(instance_name) }.unwrap_or("phstring");
        let log: Logger = match log_message {
            Some(f) => {
                let l = CLog3 { f, env };
                Box::new(move |s, c, m| l.log(s, c, m))
            }
            None => Box::new(|_, _, _| {}),
        };
        let fail = |log: &Logger, m: String| {
            log(Status::Error, "logStatusError", &m);
            std::ptr::null_mut()
        };
        if event_mode_used {
            return fail(
                &log,
                "this FMU has no event mode (hasEventMode=\"false\"); instantiate with eventModeUsed = false".into(),
            );
        }
        // SAFETY: FMI contract.
        let Some(token) = (unsafe { str_arg(token) }) else {
            return fail(&log, "instantiationToken is missing".into());
        };
        // SAFETY: FMI contract.
        let Some(dir) = (unsafe { str_arg(resource_path) }) else {
            return fail(
                &log,
                "resourcePath is missing: the FMU's scenario is a resource".into(),
            );
        };
        let path = PathBuf::from(dir).join("scenario.toml");
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(cause) => return fail(&log, FmuError::ReadScenario { path, cause }.to_string()),
        };
        match Instance::new(name, token, text, path, Box::new(|_, _, _| {}), false) {
            Ok(mut inst) => {
                inst.set_log(log, logging_on);
                inst.set_api(Api::Fmi3);
                handles::add_instance(inst) as Fmi3Instance
            }
            Err(e) => fail(&log, e.to_string()),
        }
    });
    result.unwrap_or(std::ptr::null_mut())
}

/// `fmi3FreeInstance`: frees the instance and the FMU states it saved. A handle that is
/// null, already freed or never given out is ignored (a second call does nothing).
#[unsafe(no_mangle)]
pub extern "C" fn fmi3FreeInstance(c: Fmi3Instance) {
    let _ = catch_unwind(|| handles::remove_instance(c as usize));
}

/// `fmi3SetDebugLogging`: informational messages on or off (errors are always logged).
#[unsafe(no_mangle)]
pub extern "C" fn fmi3SetDebugLogging(
    c: Fmi3Instance,
    logging_on: bool,
    _n_categories: usize,
    _categories: *const *const c_char,
) -> Fmi3Status {
    with(c, |i| {
        i.set_logging(logging_on);
        Status::Ok
    })
}

/// `fmi3EnterInitializationMode`: the experiment's start (the scenario's `t = 0`) and stop
/// time; the tolerance is not used.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3EnterInitializationMode(
    c: Fmi3Instance,
    _tolerance_defined: bool,
    _tolerance: f64,
    start_time: f64,
    stop_time_defined: bool,
    stop_time: f64,
) -> Fmi3Status {
    with(c, |i| {
        let s = i.setup_experiment(start_time, stop_time_defined.then_some(stop_time));
        if s != Status::Ok {
            return s;
        }
        i.enter_initialization()
    })
}

/// `fmi3ExitInitializationMode`: the FMU is then in step mode.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3ExitInitializationMode(c: Fmi3Instance) -> Fmi3Status {
    with(c, |i| i.exit_initialization())
}

/// `fmi3Terminate`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3Terminate(c: Fmi3Instance) -> Fmi3Status {
    with(c, |i| i.terminate())
}

/// `fmi3Reset`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3Reset(c: Fmi3Instance) -> Fmi3Status {
    with(c, |i| i.reset())
}

/// Refuses a `Float64` call whose value count differs from its variable count (all the
/// FMU's variables are scalars).
fn count_mismatch(i: &mut Instance, call: &str, n_vr: usize, n_values: usize) -> Option<Status> {
    (n_values != n_vr).then(|| {
        i.refused(&format!(
            "{call}: {n_values} values for {n_vr} scalar variables"
        ))
    })
}

/// `fmi3GetFloat64`: every variable, and `time`.
///
/// # Safety
/// `vr` holds `n_vr` and `values` `n_values` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFloat64(
    c: Fmi3Instance,
    vr: *const u32,
    n_vr: usize,
    values: *mut f64,
    n_values: usize,
) -> Fmi3Status {
    with(c, |i| {
        if let Some(s) = count_mismatch(i, "fmi3GetFloat64", n_vr, n_values) {
            return s;
        }
        // SAFETY: FMI contract.
        let (Some(vr), Some(out)) = (unsafe { slice(vr, n_vr) }, unsafe {
            slice_mut(values, n_values)
        }) else {
            return i.refused("fmi3GetFloat64: null array");
        };
        let time_vr = i.spec().time_reference();
        for (r, o) in vr.iter().zip(out.iter_mut()) {
            if *r == time_vr {
                *o = i.time();
                continue;
            }
            let s = i.get_real(std::slice::from_ref(r), std::slice::from_mut(o));
            if s != Status::Ok {
                return s;
            }
        }
        Status::Ok
    })
}

/// `fmi3SetFloat64`: parameters and inputs (`time` cannot be set).
///
/// # Safety
/// `vr` holds `n_vr` and `values` `n_values` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFloat64(
    c: Fmi3Instance,
    vr: *const u32,
    n_vr: usize,
    values: *const f64,
    n_values: usize,
) -> Fmi3Status {
    with(c, |i| {
        if let Some(s) = count_mismatch(i, "fmi3SetFloat64", n_vr, n_values) {
            return s;
        }
        // SAFETY: FMI contract.
        let (Some(vr), Some(v)) = (unsafe { slice(vr, n_vr) }, unsafe {
            slice(values, n_values)
        }) else {
            return i.refused("fmi3SetFloat64: null array");
        };
        if vr.contains(&i.spec().time_reference()) {
            return i.refused("time is the independent variable and cannot be set");
        }
        i.set_real(vr, v)
    })
}

/// `fmi3DoStep`: as `fmi2DoStep`; a discarded step sets `terminateSimulation` (a retry from
/// there fails again) and `lastSuccessfulTime` to the last internal step completed.
///
/// # Safety
/// The output pointers are valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DoStep(
    c: Fmi3Instance,
    current_communication_point: f64,
    communication_step_size: f64,
    _no_set_fmu_state_prior: bool,
    event_handling_needed: *mut bool,
    terminate_simulation: *mut bool,
    early_return: *mut bool,
    last_successful_time: *mut f64,
) -> Fmi3Status {
    with(c, |i| {
        let s = i.do_step(current_communication_point, communication_step_size);
        // SAFETY: FMI contract (each pointer is checked for null).
        unsafe {
            if !event_handling_needed.is_null() {
                *event_handling_needed = false;
            }
            if !terminate_simulation.is_null() {
                *terminate_simulation = i.mode() == Mode::StepFailed;
            }
            if !early_return.is_null() {
                *early_return = false;
            }
            if !last_successful_time.is_null() {
                *last_successful_time = i.time();
            }
        }
        s
    })
}

/// `fmi3GetFMUState`: a new saved state, or the given one overwritten.
///
/// # Safety
/// `state` is valid for reading and writing a pointer (to null or to a state of this FMU).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFMUState(c: Fmi3Instance, state: *mut Fmi3FmuState) -> Fmi3Status {
    // SAFETY: FMI contract.
    with(c, |i| unsafe {
        get_state(i, c as usize, "fmi3GetFMUState", state)
    })
}

/// `fmi3SetFMUState`: a state of this FMU (a freed or unknown handle is refused).
#[unsafe(no_mangle)]
pub extern "C" fn fmi3SetFMUState(c: Fmi3Instance, state: Fmi3FmuState) -> Fmi3Status {
    with(c, |i| set_state(i, "fmi3SetFMUState", state))
}

/// `fmi3FreeFMUState`.
///
/// # Safety
/// `state` is null or valid for reading and writing a pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeFMUState(c: Fmi3Instance, state: *mut Fmi3FmuState) -> Fmi3Status {
    // SAFETY: FMI contract.
    with(c, |i| unsafe { free_state(i, "fmi3FreeFMUState", state) })
}

/// `fmi3SerializedFMUStateSize`.
///
/// # Safety
/// `size` is a valid pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    c: Fmi3Instance,
    state: Fmi3FmuState,
    size: *mut usize,
) -> Fmi3Status {
    // SAFETY: FMI contract.
    with(c, |i| unsafe {
        state_size(i, "fmi3SerializedFMUStateSize", state, size)
    })
}

/// `fmi3SerializeFMUState`: JSON with a checksum, floats in round-trip form.
///
/// # Safety
/// `bytes` has room for `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    c: Fmi3Instance,
    state: Fmi3FmuState,
    bytes: *mut u8,
    size: usize,
) -> Fmi3Status {
    // SAFETY: FMI contract.
    with(c, |i| unsafe {
        serialize_state(
            i,
            "fmi3SerializeFMUState",
            "fmi3SerializedFMUStateSize",
            state,
            bytes,
            size,
        )
    })
}

/// `fmi3DeserializeFMUState`.
///
/// # Safety
/// `bytes` holds `size` bytes; `state` is valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    c: Fmi3Instance,
    bytes: *const u8,
    size: usize,
    state: *mut Fmi3FmuState,
) -> Fmi3Status {
    // SAFETY: FMI contract.
    with(c, |i| unsafe {
        deserialize_state(i, c as usize, "fmi3DeserializeFMUState", bytes, size, state)
    })
}

/// The FMI 3.0 calls' hint for [`no_such`].
const FLOAT64: &str = "Float64 variables (fmi3GetFloat64/fmi3SetFloat64)";

/// Getters and setters of the numeric types the FMU does not declare.
macro_rules! other_types {
    ($($name:ident: $ptr:ty;)*) => {$(
        #[doc = concat!("`", stringify!($name), "`: the FMU has no variables of this type.")]
        #[unsafe(no_mangle)]
        pub extern "C" fn $name(
            c: Fmi3Instance,
            _vr: *const u32,
            n_vr: usize,
            _values: $ptr,
            _n_values: usize,
        ) -> Fmi3Status {
            no_such(c, stringify!($name), n_vr, FLOAT64)
        }
    )*};
}

other_types! {
    fmi3GetFloat32: *mut f32;
    fmi3GetInt8: *mut i8;
    fmi3GetUInt8: *mut u8;
    fmi3GetInt16: *mut i16;
    fmi3GetUInt16: *mut u16;
    fmi3GetInt32: *mut i32;
    fmi3GetUInt32: *mut u32;
    fmi3GetInt64: *mut i64;
    fmi3GetUInt64: *mut u64;
    fmi3GetBoolean: *mut bool;
    fmi3GetString: *mut *const c_char;
    fmi3SetFloat32: *const f32;
    fmi3SetInt8: *const i8;
    fmi3SetUInt8: *const u8;
    fmi3SetInt16: *const i16;
    fmi3SetUInt16: *const u16;
    fmi3SetInt32: *const i32;
    fmi3SetUInt32: *const u32;
    fmi3SetInt64: *const i64;
    fmi3SetUInt64: *const u64;
    fmi3SetBoolean: *const bool;
    fmi3SetString: *const *const c_char;
}

/// `fmi3GetBinary`: the FMU has no Binary variables.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3GetBinary(
    c: Fmi3Instance,
    _vr: *const u32,
    n_vr: usize,
    _sizes: *mut usize,
    _values: *mut *const u8,
    _n_values: usize,
) -> Fmi3Status {
    no_such(c, "fmi3GetBinary", n_vr, FLOAT64)
}

/// `fmi3SetBinary`: the FMU has no Binary variables.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3SetBinary(
    c: Fmi3Instance,
    _vr: *const u32,
    n_vr: usize,
    _sizes: *const usize,
    _values: *const *const u8,
    _n_values: usize,
) -> Fmi3Status {
    no_such(c, "fmi3SetBinary", n_vr, FLOAT64)
}

/// `fmi3GetClock`: the FMU has no clocks.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3GetClock(
    c: Fmi3Instance,
    _vr: *const u32,
    n_vr: usize,
    _values: *mut bool,
) -> Fmi3Status {
    no_such(c, "fmi3GetClock", n_vr, FLOAT64)
}

/// `fmi3SetClock`: the FMU has no clocks.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3SetClock(
    c: Fmi3Instance,
    _vr: *const u32,
    n_vr: usize,
    _values: *const bool,
) -> Fmi3Status {
    no_such(c, "fmi3SetClock", n_vr, FLOAT64)
}

/// Functions of capabilities the FMU does not declare: each refuses with `fmi3Error` and a
/// message naming it (`$args` are the C parameters after the instance).
macro_rules! refused {
    ($($name:ident($($arg:ty),*) $why:literal;)*) => {$(
        #[doc = concat!("`", stringify!($name), "`: ", $why, ".")]
        #[unsafe(no_mangle)]
        pub extern "C" fn $name(c: Fmi3Instance, $(_: $arg),*) -> Fmi3Status {
            with(c, |i| i.refused(concat!(stringify!($name), ": ", $why)))
        }
    )*};
}

refused! {
    fmi3EnterEventMode() "the FMU has no event mode";
    fmi3EnterStepMode() "the FMU has no event mode; it is in step mode after initialization";
    fmi3UpdateDiscreteStates(*mut bool, *mut bool, *mut bool, *mut bool, *mut bool, *mut f64) "the FMU has no event mode";
    fmi3EvaluateDiscreteStates() "the FMU has no discrete states";
    fmi3GetNumberOfVariableDependencies(u32, *mut usize) "dependencies are not provided (every output depends on every input)";
    fmi3GetVariableDependencies(u32, *mut usize, *mut u32, *mut usize, *mut c_int, usize) "dependencies are not provided (every output depends on every input)";
    fmi3GetDirectionalDerivative(*const u32, usize, *const u32, usize, *const f64, usize, *mut f64, usize) "not provided (providesDirectionalDerivatives=\"false\")";
    fmi3GetAdjointDerivative(*const u32, usize, *const u32, usize, *const f64, usize, *mut f64, usize) "not provided (providesAdjointDerivatives=\"false\")";
    fmi3EnterConfigurationMode() "the FMU has no structural parameters";
    fmi3ExitConfigurationMode() "the FMU has no structural parameters";
    fmi3GetIntervalDecimal(*const u32, usize, *mut f64, *mut c_int) "the FMU has no clocks";
    fmi3GetIntervalFraction(*const u32, usize, *mut u64, *mut u64, *mut c_int) "the FMU has no clocks";
    fmi3GetShiftDecimal(*const u32, usize, *mut f64) "the FMU has no clocks";
    fmi3GetShiftFraction(*const u32, usize, *mut u64, *mut u64) "the FMU has no clocks";
    fmi3SetIntervalDecimal(*const u32, usize, *const f64) "the FMU has no clocks";
    fmi3SetIntervalFraction(*const u32, usize, *const u64, *const u64) "the FMU has no clocks";
    fmi3SetShiftDecimal(*const u32, usize, *const f64) "the FMU has no clocks";
    fmi3SetShiftFraction(*const u32, usize, *const u64, *const u64) "the FMU has no clocks";
    fmi3GetOutputDerivatives(*const u32, usize, *const i32, *mut f64, usize) "not provided (maxOutputDerivativeOrder=\"0\")";
    fmi3EnterContinuousTimeMode() "the FMU is for Co-Simulation only";
    fmi3CompletedIntegratorStep(bool, *mut bool, *mut bool) "the FMU is for Co-Simulation only";
    fmi3SetTime(f64) "the FMU is for Co-Simulation only";
    fmi3SetContinuousStates(*const f64, usize) "the FMU is for Co-Simulation only";
    fmi3GetContinuousStateDerivatives(*mut f64, usize) "the FMU is for Co-Simulation only";
    fmi3GetEventIndicators(*mut f64, usize) "the FMU is for Co-Simulation only";
    fmi3GetContinuousStates(*mut f64, usize) "the FMU is for Co-Simulation only";
    fmi3GetNominalsOfContinuousStates(*mut f64, usize) "the FMU is for Co-Simulation only";
    fmi3GetNumberOfEventIndicators(*mut usize) "the FMU is for Co-Simulation only";
    fmi3GetNumberOfContinuousStates(*mut usize) "the FMU is for Co-Simulation only";
    fmi3ActivateModelPartition(u32, f64) "the FMU is for Co-Simulation only";
}

/// `fmi3InstantiateModelExchange`: the FMU is for Co-Simulation only (null).
#[unsafe(no_mangle)]
pub extern "C" fn fmi3InstantiateModelExchange(
    _name: *const c_char,
    _token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    _env: *mut c_void,
    _log_message: Fmi3LogMessage,
) -> Fmi3Instance {
    std::ptr::null_mut()
}

/// `fmi3InstantiateScheduledExecution`: the FMU is for Co-Simulation only (null).
#[unsafe(no_mangle)]
pub extern "C" fn fmi3InstantiateScheduledExecution(
    _name: *const c_char,
    _token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    _env: *mut c_void,
    _log_message: Fmi3LogMessage,
    _clock_update: *const c_void,
    _lock_preemption: *const c_void,
    _unlock_preemption: *const c_void,
) -> Fmi3Instance {
    std::ptr::null_mut()
}
