//! The FMI 2.0 Co-Simulation C interface: the 34 functions of `fmi2Functions.h`, each a thin
//! conversion of C arguments to a call on [`Instance`]. Every function catches panics and
//! checks its pointers; a null array, or an instance or state handle that is null, freed or
//! never given out (the handles are registered, not addresses: see `handles`), is an
//! `fmi2Error`, never a crash. Calls on one instance are serialized by its lock.

use std::ffi::{CStr, CString, c_char, c_int, c_uint, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

use crate::error::FmuError;
use crate::handles;
use crate::instance::{Instance, Logger, Saved, Status, lock};

/// `fmi2Status` as the C `int` it is.
pub type Fmi2Status = c_int;
/// `fmi2Component`: a pointer to an instance.
pub type Fmi2Component = *mut c_void;
/// `fmi2FMUstate`: a pointer to a saved state.
pub type Fmi2FmuState = *mut c_void;

/// `fmi2CallbackLogger`.
pub type Fmi2Logger = Option<
    unsafe extern "C" fn(
        env: *mut c_void,
        instance_name: *const c_char,
        status: c_int,
        category: *const c_char,
        message: *const c_char,
        ...
    ),
>;

/// `fmi2CallbackFunctions`.
#[repr(C)]
pub struct Fmi2CallbackFunctions {
    /// Log callback (may be null: then nothing is logged).
    pub logger: Fmi2Logger,
    /// Allocator (unused: `canNotUseMemoryManagementFunctions`).
    pub allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    /// Deallocator (unused).
    pub free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    /// Asynchronous step callback (unused).
    pub step_finished: Option<unsafe extern "C" fn(*mut c_void, c_int)>,
    /// The master's environment pointer, passed back to the logger.
    pub component_environment: *mut c_void,
}

/// `fmi2CoSimulation` of `fmi2Type`.
const FMI2_CO_SIMULATION: c_int = 1;

const OK: Fmi2Status = Status::Ok as c_int;
const DISCARD: Fmi2Status = Status::Discard as c_int;
const ERROR: Fmi2Status = Status::Error as c_int;
const FATAL: Fmi2Status = Status::Fatal as c_int;

/// The logger of an instance: the master's callback with its environment.
struct CLogger {
    f: unsafe extern "C" fn(*mut c_void, *const c_char, c_int, *const c_char, *const c_char, ...),
    env: *mut c_void,
    name: CString,
}

// SAFETY: the FMI standard lets an instance be called from any thread (one call at a time);
// the environment pointer is the master's and only passed back to it.
unsafe impl Send for CLogger {}

impl CLogger {
    fn log(&self, status: Status, category: &str, message: &str) {
        let category = c_string(category);
        // The message is the format string (FMI 2.0 §2.1.5): `%` doubled for the printf-style
        // formatting of the master's logger, `#` doubled since `#…#` marks a value
        // reference. A logger that does not format shows the doubled characters.
        let message = c_string(&message.replace('%', "%%").replace('#', "##"));
        // SAFETY: `f` is the master's logger, called with valid NUL-terminated strings and
        // no variable arguments (the format has no conversions).
        unsafe {
            (self.f)(
                self.env,
                self.name.as_ptr(),
                status as c_int,
                category.as_ptr(),
                message.as_ptr(),
            );
        }
    }
}

/// `s` as a C string, interior NULs replaced.
pub(crate) fn c_string(s: &str) -> CString {
    CString::new(s.replace('\0', " ")).unwrap_or_default()
}

/// A C string argument, if not null and UTF-8.
///
/// # Safety
/// `p` is null or a NUL-terminated string valid for the call.
pub(crate) unsafe fn str_arg<'a>(p: *const c_char) -> Option<&'a str> {
    if p.is_null() {
        return None;
    }
    // SAFETY: by the caller's contract.
    unsafe { CStr::from_ptr(p) }.to_str().ok()
}

/// Runs `f` on the instance `c` (of either FMI version), under its lock: calls on one
/// instance from several threads run one at a time. A handle that is null, freed or never
/// given out, a call from within the master's logger during a call on the same instance,
/// and a panic are errors.
pub(crate) fn with<F>(c: Fmi2Component, f: F) -> Fmi2Status
where
    F: FnOnce(&mut Instance) -> Status,
{
    let Some(cell) = handles::instance(c as usize) else {
        return ERROR;
    };
    let Some(_entered) = handles::Entered::new(c as usize) else {
        return ERROR;
    };
    let mut guard = lock(&cell);
    let inst = &mut *guard;
    match catch_unwind(AssertUnwindSafe(|| f(inst))) {
        Ok(s) => s as c_int,
        Err(_) => {
            // The simulation may be half-updated: only getters, reset and free remain.
            inst.poison();
            let _ = catch_unwind(AssertUnwindSafe(|| {
                inst.log(
                    Status::Fatal,
                    "logStatusError",
                    "internal error (a panic in phstring); please report it with the scenario",
                )
            }));
            FATAL
        }
    }
}

/// A slice from a C array, if the pointer is non-null (or the length is 0).
///
/// # Safety
/// `p` points to `n` valid elements, or `n == 0`.
pub(crate) unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        return Some(&[]);
    }
    if p.is_null() {
        return None;
    }
    // SAFETY: by the caller's contract.
    Some(unsafe { std::slice::from_raw_parts(p, n) })
}

/// A mutable slice from a C array.
///
/// # Safety
/// As [`slice`], and the elements are writable and not aliased.
pub(crate) unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        return Some(&mut []);
    }
    if p.is_null() {
        return None;
    }
    // SAFETY: by the caller's contract.
    Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

/// The folder of a `file:` URI (`file:///path`, `file:/path`, `file://localhost/path`),
/// percent-decoded.
pub fn resource_dir(uri: &str) -> Result<PathBuf, FmuError> {
    let rest = uri
        .strip_prefix("file://localhost")
        .or_else(|| uri.strip_prefix("file://"))
        .or_else(|| uri.strip_prefix("file:"))
        .ok_or_else(|| FmuError::NotAFileUri { uri: uri.into() })?;
    let bytes = rest.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok();
            if let Some(b) = hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                out.push(b);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    let path = String::from_utf8(out).map_err(|_| FmuError::UriNotUtf8 { uri: uri.into() })?;
    // `file:///C:/x` on Windows: drop the slash before the drive letter.
    let path = match path.as_bytes() {
        [b'/', d, b':', ..] if cfg!(windows) && d.is_ascii_alphabetic() => path[1..].to_string(),
        _ => path,
    };
    Ok(PathBuf::from(path))
}

/// `fmi2GetTypesPlatform`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// `fmi2GetVersion`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// `fmi2Instantiate`: reads `resources/scenario.toml` and checks the GUID. Null on failure,
/// with the reason logged.
///
/// # Safety
/// The pointers follow the FMI 2.0 contract (valid strings, a valid callback struct or null).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: *const c_char,
    fmu_type: c_int,
    guid: *const c_char,
    resource_location: *const c_char,
    functions: *const Fmi2CallbackFunctions,
    _visible: c_int,
    logging_on: c_int,
) -> Fmi2Component {
    let result = catch_unwind(|| {
        // SAFETY: FMI contract.
        let name = unsafe { str_arg(instance_name) }.unwrap_or("phstring");
        let logger = if functions.is_null() {
            None
        } else {
            // SAFETY: non-null and valid by the FMI contract.
            let cb = unsafe { &*functions };
            cb.logger.map(|f| CLogger {
                f,
                env: cb.component_environment,
                name: c_string(name),
            })
        };
        let log: Logger = match logger {
            Some(l) => Box::new(move |s, c, m| l.log(s, c, m)),
            None => Box::new(|_, _, _| {}),
        };
        let fail = |log: &Logger, m: String| {
            log(Status::Error, "logStatusError", &m);
            std::ptr::null_mut()
        };
        if fmu_type != FMI2_CO_SIMULATION {
            return fail(
                &log,
                format!(
                    "this FMU is for Co-Simulation only (fmuType = 1), got fmuType = {fmu_type}"
                ),
            );
        }
        // SAFETY: FMI contract.
        let Some(guid) = (unsafe { str_arg(guid) }) else {
            return fail(&log, "fmuGUID is missing".into());
        };
        // SAFETY: FMI contract.
        let Some(uri) = (unsafe { str_arg(resource_location) }) else {
            return fail(&log, "fmuResourceLocation is missing".into());
        };
        let dir = match resource_dir(uri) {
            Ok(d) => d,
            Err(e) => return fail(&log, e.to_string()),
        };
        let path = dir.join("scenario.toml");
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(cause) => return fail(&log, FmuError::ReadScenario { path, cause }.to_string()),
        };
        match Instance::new(name, guid, text, path, Box::new(|_, _, _| {}), false) {
            Ok(mut inst) => {
                inst.set_log(log, logging_on != 0);
                handles::add_instance(inst) as Fmi2Component
            }
            Err(e) => fail(&log, e.to_string()),
        }
    });
    result.unwrap_or(std::ptr::null_mut())
}

/// `fmi2FreeInstance`: frees the instance and the FMU states it saved. A handle that is
/// null, already freed or never given out is ignored (a second call does nothing).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2FreeInstance(c: Fmi2Component) {
    let _ = catch_unwind(|| handles::remove_instance(c as usize));
}

/// `fmi2SetDebugLogging`: turns informational messages on or off (errors are always
/// logged); the categories are not filtered.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetDebugLogging(
    c: Fmi2Component,
    logging_on: c_int,
    _n_categories: usize,
    _categories: *const *const c_char,
) -> Fmi2Status {
    with(c, |i| {
        i.set_logging(logging_on != 0);
        Status::Ok
    })
}

/// `fmi2SetupExperiment` (the tolerance is not used: the scenario's `newton.tol` and
/// `time.rtol`/`time.atol` govern accuracy).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetupExperiment(
    c: Fmi2Component,
    _tolerance_defined: c_int,
    _tolerance: f64,
    start_time: f64,
    stop_time_defined: c_int,
    stop_time: f64,
) -> Fmi2Status {
    with(c, |i| {
        i.setup_experiment(start_time, (stop_time_defined != 0).then_some(stop_time))
    })
}

/// `fmi2EnterInitializationMode`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2EnterInitializationMode(c: Fmi2Component) -> Fmi2Status {
    with(c, Instance::enter_initialization)
}

/// `fmi2ExitInitializationMode`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2ExitInitializationMode(c: Fmi2Component) -> Fmi2Status {
    with(c, Instance::exit_initialization)
}

/// `fmi2Terminate`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2Terminate(c: Fmi2Component) -> Fmi2Status {
    with(c, Instance::terminate)
}

/// `fmi2Reset`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2Reset(c: Fmi2Component) -> Fmi2Status {
    with(c, Instance::reset)
}

/// `fmi2GetReal`.
///
/// # Safety
/// `vr` and `value` point to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: Fmi2Component,
    vr: *const c_uint,
    n: usize,
    value: *mut f64,
) -> Fmi2Status {
    with(c, |i| {
        // SAFETY: FMI contract.
        match unsafe { (slice(vr, n), slice_mut(value, n)) } {
            (Some(vr), Some(out)) => i.get_real(vr, out),
            _ => i.refused("fmi2GetReal: null array"),
        }
    })
}

/// `fmi2SetReal`.
///
/// # Safety
/// `vr` and `value` point to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: Fmi2Component,
    vr: *const c_uint,
    n: usize,
    value: *const f64,
) -> Fmi2Status {
    with(c, |i| {
        // SAFETY: FMI contract.
        match unsafe { (slice(vr, n), slice(value, n)) } {
            (Some(vr), Some(v)) => i.set_real(vr, v),
            _ => i.refused("fmi2SetReal: null array"),
        }
    })
}

/// A variable type the FMU does not declare: nothing to do for zero variables, an error for
/// any other (`hint` names the type the FMU has and its calls).
pub(crate) fn no_such(c: Fmi2Component, what: &str, n: usize, hint: &str) -> Fmi2Status {
    with(c, |i| {
        if n == 0 {
            return Status::Ok;
        }
        i.refused(&format!("{what}: this FMU has only {hint}"))
    })
}

/// The FMI 2.0 calls' hint for [`no_such`].
const REAL: &str = "Real variables (fmi2GetReal/fmi2SetReal)";

/// `fmi2GetInteger` (no Integer variables).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetInteger(
    c: Fmi2Component,
    _vr: *const c_uint,
    n: usize,
    _value: *mut c_int,
) -> Fmi2Status {
    no_such(c, "fmi2GetInteger", n, REAL)
}

/// `fmi2GetBoolean` (no Boolean variables).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetBoolean(
    c: Fmi2Component,
    _vr: *const c_uint,
    n: usize,
    _value: *mut c_int,
) -> Fmi2Status {
    no_such(c, "fmi2GetBoolean", n, REAL)
}

/// `fmi2GetString` (no String variables).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetString(
    c: Fmi2Component,
    _vr: *const c_uint,
    n: usize,
    _value: *mut *const c_char,
) -> Fmi2Status {
    no_such(c, "fmi2GetString", n, REAL)
}

/// `fmi2SetInteger` (no Integer variables).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetInteger(
    c: Fmi2Component,
    _vr: *const c_uint,
    n: usize,
    _value: *const c_int,
) -> Fmi2Status {
    no_such(c, "fmi2SetInteger", n, REAL)
}

/// `fmi2SetBoolean` (no Boolean variables).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetBoolean(
    c: Fmi2Component,
    _vr: *const c_uint,
    n: usize,
    _value: *const c_int,
) -> Fmi2Status {
    no_such(c, "fmi2SetBoolean", n, REAL)
}

/// `fmi2SetString` (no String variables).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetString(
    c: Fmi2Component,
    _vr: *const c_uint,
    n: usize,
    _value: *const *const c_char,
) -> Fmi2Status {
    no_such(c, "fmi2SetString", n, REAL)
}

/// `GetFMUstate` of either version (`call` names it in messages) on instance `owner` (its
/// handle): a new saved state, or the given one overwritten.
///
/// # Safety
/// `state` is null or points to a writable state handle (null or one of ours).
pub(crate) unsafe fn get_state(
    i: &mut Instance,
    owner: usize,
    call: &str,
    state: *mut *mut c_void,
) -> Status {
    if state.is_null() {
        return i.refused(&format!("{call}: null FMU state pointer"));
    }
    match i.save() {
        // SAFETY: by the caller's contract.
        Ok(saved) => match unsafe { put_state(state, owner, saved) } {
            Ok(()) => Status::Ok,
            Err(m) => i.refused(&format!("{call}: {m}")),
        },
        Err(m) => i.refused(&format!("{call}: {m}")),
    }
}

/// Stores `saved` (saved by instance `owner`) at `*state`: a new state, or the existing one
/// overwritten (FMI: a non-null `*state` is a state of ours, to be reused).
///
/// # Safety
/// `state` is valid for reading and writing a pointer.
unsafe fn put_state(state: *mut *mut c_void, owner: usize, saved: Saved) -> Result<(), FmuError> {
    // SAFETY: by the caller's contract.
    let current = unsafe { *state };
    if current.is_null() {
        // SAFETY: by the caller's contract.
        unsafe { *state = handles::add_state(owner, saved) as *mut c_void };
        Ok(())
    } else if handles::replace_state(current as usize, saved) {
        Ok(())
    } else {
        Err(FmuError::NotAState)
    }
}

/// `SetFMUstate` of either version: refused for a handle that is not a live state.
pub(crate) fn set_state(i: &mut Instance, call: &str, state: *mut c_void) -> Status {
    match handles::state(state as usize) {
        Some(saved) => i.restore(&saved),
        None if state.is_null() => i.refused(&format!("{call}: null FMU state")),
        None => i.refused(&format!("{call}: {}", FmuError::NotAState)),
    }
}

/// `FreeFMUstate` of either version: frees `*state` and sets it to null (a null pointer or
/// null state is nothing to free).
///
/// # Safety
/// `state` is null or valid for reading and writing a pointer.
pub(crate) unsafe fn free_state(i: &mut Instance, call: &str, state: *mut *mut c_void) -> Status {
    if state.is_null() {
        return Status::Ok;
    }
    // SAFETY: by the caller's contract.
    let current = unsafe { *state };
    if current.is_null() {
        return Status::Ok;
    }
    if !handles::remove_state(current as usize) {
        return i.refused(&format!("{call}: {}", FmuError::NotAState));
    }
    // SAFETY: by the caller's contract.
    unsafe { *state = std::ptr::null_mut() };
    Status::Ok
}

/// The serialized form of saved state `state` ([`Saved::to_bytes`]).
fn serialize(i: &mut Instance, call: &str, state: *mut c_void) -> Result<Vec<u8>, Status> {
    let Some(saved) = handles::state(state as usize) else {
        return Err(i.refused(&format!("{call}: {}", FmuError::NotAState)));
    };
    saved
        .to_bytes()
        .map_err(|e| i.refused(&format!("{call}: {e}")))
}

/// `SerializedFMUstateSize` of either version.
///
/// # Safety
/// `size` is null or valid for writing.
pub(crate) unsafe fn state_size(
    i: &mut Instance,
    call: &str,
    state: *mut c_void,
    size: *mut usize,
) -> Status {
    if size.is_null() {
        return i.refused(&format!("{call}: null size pointer"));
    }
    match serialize(i, call, state) {
        // SAFETY: checked for null above; valid by the caller's contract.
        Ok(data) => unsafe { *size = data.len() },
        Err(s) => return s,
    }
    Status::Ok
}

/// `SerializeFMUstate` of either version (`size_call` names the size function).
///
/// # Safety
/// `bytes` is null or has room for `size` bytes.
pub(crate) unsafe fn serialize_state(
    i: &mut Instance,
    call: &str,
    size_call: &str,
    state: *mut c_void,
    bytes: *mut u8,
    size: usize,
) -> Status {
    let data = match serialize(i, call, state) {
        Ok(d) => d,
        Err(s) => return s,
    };
    // SAFETY: by the caller's contract.
    let Some(out) = (unsafe { slice_mut(bytes, size) }) else {
        return i.refused(&format!("{call}: null buffer"));
    };
    if out.len() != data.len() {
        return i.refused(&format!(
            "{call}: the buffer has {} bytes, the state {} ({size_call})",
            out.len(),
            data.len()
        ));
    }
    out.copy_from_slice(&data);
    Status::Ok
}

/// `DeSerializeFMUstate` of either version, on instance `owner` (its handle).
///
/// # Safety
/// `bytes` is null or holds `size` bytes; `state` is null or valid for reading and writing
/// a pointer.
pub(crate) unsafe fn deserialize_state(
    i: &mut Instance,
    owner: usize,
    call: &str,
    bytes: *const u8,
    size: usize,
    state: *mut *mut c_void,
) -> Status {
    // SAFETY: by the caller's contract.
    let Some(data) = (unsafe { slice(bytes, size) }) else {
        return i.refused(&format!("{call}: null buffer"));
    };
    if state.is_null() {
        return i.refused(&format!("{call}: null FMU state pointer"));
    }
    let put = Saved::from_bytes(data).and_then(|saved| {
        // SAFETY: by the caller's contract.
        unsafe { put_state(state, owner, saved) }
    });
    match put {
        Ok(()) => Status::Ok,
        Err(e) => i.refused(&format!("{call}: {e}")),
    }
}

/// `fmi2GetFMUstate`: a new saved state, or the given one overwritten.
///
/// # Safety
/// `state` is valid for reading and writing a pointer (to null or to a state of this FMU).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(c: Fmi2Component, state: *mut Fmi2FmuState) -> Fmi2Status {
    // SAFETY: FMI contract.
    with(c, |i| unsafe {
        get_state(i, c as usize, "fmi2GetFMUstate", state)
    })
}

/// `fmi2SetFMUstate`: a state from `fmi2GetFMUstate` or `fmi2DeSerializeFMUstate` (a freed
/// or unknown handle is refused).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetFMUstate(c: Fmi2Component, state: Fmi2FmuState) -> Fmi2Status {
    with(c, |i| set_state(i, "fmi2SetFMUstate", state))
}

/// `fmi2FreeFMUstate`.
///
/// # Safety
/// `state` is null or valid for reading and writing a pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: Fmi2Component,
    state: *mut Fmi2FmuState,
) -> Fmi2Status {
    // SAFETY: FMI contract.
    with(c, |i| unsafe { free_state(i, "fmi2FreeFMUstate", state) })
}

/// `fmi2SerializedFMUstateSize`.
///
/// # Safety
/// `size` is a valid pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: Fmi2Component,
    state: Fmi2FmuState,
    size: *mut usize,
) -> Fmi2Status {
    // SAFETY: FMI contract.
    with(c, |i| unsafe {
        state_size(i, "fmi2SerializedFMUstateSize", state, size)
    })
}

/// `fmi2SerializeFMUstate`: JSON with a checksum, floats in round-trip form.
///
/// # Safety
/// `bytes` has room for `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: Fmi2Component,
    state: Fmi2FmuState,
    bytes: *mut c_char,
    size: usize,
) -> Fmi2Status {
    // SAFETY: FMI contract.
    with(c, |i| unsafe {
        serialize_state(
            i,
            "fmi2SerializeFMUstate",
            "fmi2SerializedFMUstateSize",
            state,
            bytes as *mut u8,
            size,
        )
    })
}

/// `fmi2DeSerializeFMUstate`.
///
/// # Safety
/// `bytes` holds `size` bytes; `state` is a valid pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: Fmi2Component,
    bytes: *const c_char,
    size: usize,
    state: *mut Fmi2FmuState,
) -> Fmi2Status {
    // SAFETY: FMI contract.
    with(c, |i| unsafe {
        deserialize_state(
            i,
            c as usize,
            "fmi2DeSerializeFMUstate",
            bytes as *const u8,
            size,
            state,
        )
    })
}

/// `fmi2GetDirectionalDerivative`: not provided (`providesDirectionalDerivative="false"`).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetDirectionalDerivative(
    c: Fmi2Component,
    _unknown: *const c_uint,
    _n_unknown: usize,
    _known: *const c_uint,
    _n_known: usize,
    _dv_known: *const f64,
    _dv_unknown: *mut f64,
) -> Fmi2Status {
    with(c, |i| {
        i.refused("fmi2GetDirectionalDerivative is not provided by this FMU")
    })
}

/// `fmi2SetRealInputDerivatives`: not supported (`canInterpolateInputs="false"`).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetRealInputDerivatives(
    c: Fmi2Component,
    _vr: *const c_uint,
    _n: usize,
    _order: *const c_int,
    _value: *const f64,
) -> Fmi2Status {
    with(c, |i| {
        i.refused("fmi2SetRealInputDerivatives: this FMU holds inputs constant over a communication step (canInterpolateInputs=\"false\")")
    })
}

/// `fmi2GetRealOutputDerivatives`: not supported (`maxOutputDerivativeOrder="0"`).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetRealOutputDerivatives(
    c: Fmi2Component,
    _vr: *const c_uint,
    _n: usize,
    _order: *const c_int,
    _value: *mut f64,
) -> Fmi2Status {
    with(c, |i| {
        i.refused("fmi2GetRealOutputDerivatives: not provided (maxOutputDerivativeOrder=\"0\")")
    })
}

/// `fmi2DoStep`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2DoStep(
    c: Fmi2Component,
    current_communication_point: f64,
    communication_step_size: f64,
    _no_set_fmu_state_prior: c_int,
) -> Fmi2Status {
    with(c, |i| {
        i.do_step(current_communication_point, communication_step_size)
    })
}

/// `fmi2CancelStep`: steps are synchronous, there is nothing to cancel.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2CancelStep(c: Fmi2Component) -> Fmi2Status {
    with(c, |i| {
        i.refused("fmi2CancelStep: this FMU steps synchronously")
    })
}

/// `fmi2GetStatus`: `fmi2DoStepStatus` is the mode's status; others are not provided.
///
/// # Safety
/// `value` is a valid pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStatus(
    c: Fmi2Component,
    kind: c_int,
    value: *mut c_int,
) -> Fmi2Status {
    with(c, |i| {
        if value.is_null() || kind != 0 {
            return i.refused("fmi2GetStatus: only fmi2DoStepStatus is provided");
        }
        let s = match i.mode() {
            crate::instance::Mode::StepFailed => DISCARD,
            crate::instance::Mode::Error => ERROR,
            _ => OK,
        };
        // SAFETY: FMI contract.
        unsafe { *value = s };
        Status::Ok
    })
}

/// `fmi2GetRealStatus`: `fmi2LastSuccessfulTime` (kind 2) is the time of the last internal
/// step completed [s].
///
/// # Safety
/// `value` is a valid pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: Fmi2Component,
    kind: c_int,
    value: *mut f64,
) -> Fmi2Status {
    with(c, |i| {
        if value.is_null() || kind != 2 {
            return i.refused("fmi2GetRealStatus: only fmi2LastSuccessfulTime is provided");
        }
        // SAFETY: FMI contract.
        unsafe { *value = i.time() };
        Status::Ok
    })
}

/// `fmi2GetIntegerStatus`: not provided.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetIntegerStatus(
    c: Fmi2Component,
    _kind: c_int,
    _value: *mut c_int,
) -> Fmi2Status {
    with(c, |i| i.refused("fmi2GetIntegerStatus is not provided"))
}

/// `fmi2GetBooleanStatus`: `fmi2Terminated` (kind 3) is true after a discarded step: the
/// FMU already halved its internal step down to the floor, so a retry from the same state
/// with the same inputs fails again (a master may still restore an earlier FMU state).
///
/// # Safety
/// `value` is a valid pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: Fmi2Component,
    kind: c_int,
    value: *mut c_int,
) -> Fmi2Status {
    with(c, |i| {
        if value.is_null() || kind != 3 {
            return i.refused("fmi2GetBooleanStatus: only fmi2Terminated is provided");
        }
        let failed = i.mode() == crate::instance::Mode::StepFailed;
        // SAFETY: FMI contract.
        unsafe { *value = c_int::from(failed) };
        Status::Ok
    })
}

/// `fmi2GetStringStatus`: not provided.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetStringStatus(
    c: Fmi2Component,
    _kind: c_int,
    _value: *mut *const c_char,
) -> Fmi2Status {
    with(c, |i| i.refused("fmi2GetStringStatus is not provided"))
}
