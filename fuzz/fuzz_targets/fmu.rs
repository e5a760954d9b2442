//! Fuzz target: the FMU's C functions (FMI 2.0 and 3.0, in-process through the
//! `phstring-fmu` rlib) called in random order with random values, as a careless or hostile
//! master would: instantiate (with the right or a wrong GUID and resource folder), set up,
//! set parameters and inputs, step, read, save, serialize (and corrupt), deserialize,
//! restore, reset, terminate and free, with freed handles used again.
//!
//! Must hold whatever the sequence: no crash, no hang, no panic inside the library (an
//! `fmi2Fatal` is one), and a step that returns `fmi2OK` has reached the master's time with
//! finite outputs. The scenario is a small wire (8 elements) with a force and a position
//! input; communication steps are kept to at most 64 internal steps so that a run stays
//! short.
#![no_main]

use std::ffi::{CString, c_char, c_int, c_void};
use std::path::PathBuf;
use std::sync::OnceLock;

use libfuzzer_sys::arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use phstring_fmu::ffi::*;
use phstring_fmu::ffi3::*;
use phstring_fmu::model::{Causality, ModelSpec};

/// A 2 m wire, EA = 1e5 N, fixed at the left, with a force input at its middle and a
/// position input at its right end.
const SCENARIO: &str = r#"
dimension = 2
[geometry]
start = [0.0, 0.0]
end = [2.0, 0.0]
[mesh]
elements = 8
[material]
law = "linear_elastic"
ea = 1e5
rho_a = 0.5
[body_force]
gravity = [0.0, -9.81]
[[boundary]]
node = 0
fixed = true
[[boundary]]
node = 4
force = ["0", "-1"]
external = true
[[boundary]]
node = -1
position = ["2.0", "0.0"]
external = true
[time]
h = 1e-3
end = 0.1
[fmu]
nodes = [4]
"#;

/// The packaged scenario: its resource folder (FMI 2.0 URI and FMI 3.0 path), GUID and
/// variables.
struct Fmu {
    uri: CString,
    path: CString,
    guid: CString,
    spec: ModelSpec,
}

fn fmu() -> &'static Fmu {
    static FMU: OnceLock<Fmu> = OnceLock::new();
    FMU.get_or_init(|| {
        let dir: PathBuf =
            std::env::temp_dir().join(format!("phstring-fuzz-fmu-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("scenario.toml"), SCENARIO).unwrap();
        let file = phstring_io::scenario::parse(SCENARIO, &dir.join("scenario.toml"), &[]).unwrap();
        let spec = ModelSpec::new(&file).unwrap();
        Fmu {
            uri: CString::new(format!("file://{}", dir.display())).unwrap(),
            path: CString::new(dir.display().to_string()).unwrap(),
            guid: CString::new(spec.guid.clone()).unwrap(),
            spec,
        }
    })
}

/// The FMI 3.0 logger: the message must be a valid C string.
unsafe extern "C" fn log3(_env: *mut c_void, _status: c_int, c: *const c_char, m: *const c_char) {
    assert!(!c.is_null() && !m.is_null());
    // SAFETY: the library passes NUL-terminated strings.
    let _ = unsafe { std::ffi::CStr::from_ptr(m) }.to_bytes().len();
}

/// A float the fuzzer picks: a sane value, a nasty one, or any bit pattern.
fn float(u: &mut Unstructured) -> Result<f64> {
    const NASTY: [f64; 14] = [
        0.0,
        -0.0,
        -1.0,
        1e-3,
        0.01,
        0.5,
        1e10,
        1e17,
        1e300,
        5e-324,
        f64::MAX,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    Ok(match u.int_in_range(0..=3u8)? {
        0 => f64::from_bits(u.arbitrary()?),
        1 => NASTY[u.choose_index(NASTY.len())?],
        _ => f64::from(u.int_in_range(-1000..=1000i16)?) * 1e-3,
    })
}

/// Up to this many instances and saved states are held at once (freed ones stay in their
/// slot, to be used again).
const SLOTS: usize = 3;

/// The fuzzed master's state.
struct Master {
    instances: [usize; SLOTS],
    states: [usize; SLOTS],
    /// The last serialized state, perhaps corrupted.
    bytes: Vec<u8>,
}

/// Asserts that a call did not panic inside the library.
fn no_fatal(s: c_int) -> c_int {
    assert_ne!(s, 4, "fmi2Fatal: a panic inside the FMU");
    s
}

/// After an `fmi2OK` step to `end` [s]: the FMU is at `end` and its outputs are finite.
fn check_step(c: Fmi2Component, end: f64) {
    let mut t = 0.0;
    // SAFETY: `t` is a valid pointer.
    assert_eq!(unsafe { fmi2GetRealStatus(c, 2, &mut t) }, 0);
    assert_eq!(t, end, "an fmi2OK step that did not reach t + H");
    let spec = &fmu().spec;
    for (vr, v) in spec.variables.iter().enumerate() {
        if v.causality == Causality::Output {
            let (vr, mut x) = (vr as u32, f64::NAN);
            // SAFETY: one valid element each.
            assert_eq!(unsafe { fmi2GetReal(c, &vr, 1, &mut x) }, 0);
            assert!(x.is_finite(), "{} = {x} after an fmi2OK step", v.name);
        }
    }
}

/// The largest communication step [s] taken at the internal step `h` [s] of instance `c`.
fn longest_step(c: Fmi2Component) -> f64 {
    let spec = &fmu().spec;
    let vr = spec.variables.iter().position(|v| v.name == "h").unwrap() as u32;
    let mut h = 0.0;
    // SAFETY: one valid element each.
    if unsafe { fmi2GetReal(c, &vr, 1, &mut h) } != 0 || !(h > 0.0) {
        return 0.0;
    }
    64.0 * h.min(1e-3)
}

impl Master {
    fn instance(&self, u: &mut Unstructured) -> Result<Fmi2Component> {
        Ok(self.instances[u.choose_index(SLOTS)?] as Fmi2Component)
    }

    fn instantiate(&mut self, u: &mut Unstructured, v3: bool) -> Result<()> {
        let f = fmu();
        let good = u.ratio(7u8, 8u8)?;
        let wrong = CString::new("{00000000-0000-0000-0000-000000000000}").unwrap();
        let guid = if good { &f.guid } else { &wrong };
        let c = if v3 {
            // SAFETY: valid strings and a valid logger.
            unsafe {
                fmi3InstantiateCoSimulation(
                    c"fuzz3".as_ptr(),
                    guid.as_ptr(),
                    f.path.as_ptr(),
                    false,
                    u.arbitrary()?,
                    u.ratio(1u8, 16u8)?,
                    false,
                    std::ptr::null(),
                    0,
                    std::ptr::null_mut(),
                    Some(log3),
                    std::ptr::null(),
                )
            }
        } else {
            // SAFETY: valid strings, no callbacks.
            unsafe {
                fmi2Instantiate(
                    c"fuzz".as_ptr(),
                    if u.ratio(1u8, 16u8)? { 0 } else { 1 },
                    guid.as_ptr(),
                    f.uri.as_ptr(),
                    std::ptr::null(),
                    0,
                    0,
                )
            }
        };
        let slot = u.choose_index(SLOTS)?;
        // The instance it replaces in the slot is freed (a master keeps no handle it lost).
        fmi2FreeInstance(self.instances[slot] as Fmi2Component);
        self.instances[slot] = c as usize;
        Ok(())
    }

    /// One call (an error when the input is used up).
    fn call(&mut self, u: &mut Unstructured) -> Result<()> {
        let n_vars = fmu().spec.variables.len() as u32;
        let c = self.instance(u)?;
        match u.int_in_range(0..=19u8)? {
            0 => self.instantiate(u, false)?,
            1 => self.instantiate(u, true)?,
            2 => fmi2FreeInstance(c),
            3 => fmi3FreeInstance(c),
            4 => {
                let (start, stop) = (float(u)?, float(u)?);
                no_fatal(fmi2SetupExperiment(
                    c,
                    0,
                    0.0,
                    start,
                    c_int::from(u.arbitrary::<bool>()?),
                    stop,
                ));
            }
            5 => {
                no_fatal(fmi2EnterInitializationMode(c));
            }
            6 => {
                no_fatal(fmi2ExitInitializationMode(c));
            }
            7 => {
                let vr = u.int_in_range(0..=n_vars + 1)?;
                let x = float(u)?;
                // SAFETY: one valid element each.
                no_fatal(unsafe { fmi2SetReal(c, &vr, 1, &x) });
            }
            8 => {
                let vrs: Vec<u32> = (0..u.int_in_range(0..=4u8)?)
                    .map(|_| u.int_in_range(0..=n_vars))
                    .collect::<Result<_>>()?;
                let mut out = vec![0.0; vrs.len()];
                // SAFETY: arrays of vrs.len() elements.
                no_fatal(unsafe { fmi2GetReal(c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) });
            }
            9 | 10 | 11 => {
                // Mostly from where the FMU is, with a step it can take in a moment.
                let mut now = 0.0;
                // SAFETY: a valid pointer.
                let known = unsafe { fmi2GetRealStatus(c, 2, &mut now) } == 0;
                let t = if known && u.ratio(7u8, 8u8)? {
                    now
                } else {
                    float(u)?
                };
                let longest = longest_step(c);
                let comm = match u.int_in_range(0..=3u8)? {
                    0 => float(u)?,
                    _ => longest * f64::from(u.int_in_range(1..=64u8)?) / 64.0,
                };
                if comm.is_finite() && comm > longest {
                    return Ok(());
                }
                let s = no_fatal(fmi2DoStep(c, t, comm, 0));
                if s == 0 {
                    check_step(c, t + comm);
                }
            }
            12 => {
                let slot = u.choose_index(SLOTS)?;
                let mut s = self.states[slot] as Fmi2FmuState;
                // SAFETY: a valid pointer to a handle.
                no_fatal(unsafe { fmi2GetFMUstate(c, &mut s) });
                self.states[slot] = s as usize;
            }
            13 => {
                let s = self.states[u.choose_index(SLOTS)?] as Fmi2FmuState;
                no_fatal(fmi2SetFMUstate(c, s));
            }
            14 => {
                let slot = u.choose_index(SLOTS)?;
                let mut s = self.states[slot] as Fmi2FmuState;
                // SAFETY: a valid pointer to a handle.
                no_fatal(unsafe { fmi2FreeFMUstate(c, &mut s) });
                // Sometimes the master keeps the freed handle.
                if u.arbitrary()? {
                    self.states[slot] = s as usize;
                }
            }
            15 => {
                let s = self.states[u.choose_index(SLOTS)?] as Fmi2FmuState;
                let mut size = 0usize;
                // SAFETY: valid pointers; the buffer has `size` bytes.
                unsafe {
                    if no_fatal(fmi2SerializedFMUstateSize(c, s, &mut size)) == 0 {
                        let mut bytes = vec![0u8; size];
                        if no_fatal(fmi2SerializeFMUstate(
                            c,
                            s,
                            bytes.as_mut_ptr() as *mut c_char,
                            size,
                        )) == 0
                        {
                            self.bytes = bytes;
                        }
                    }
                }
            }
            16 => {
                // Corrupt the serialized state: a byte changed, or cut.
                if !self.bytes.is_empty() {
                    let i = u.choose_index(self.bytes.len())?;
                    if u.arbitrary()? {
                        self.bytes[i] = u.arbitrary()?;
                    } else {
                        self.bytes.truncate(i);
                    }
                }
            }
            17 => {
                let slot = u.choose_index(SLOTS)?;
                let mut s = self.states[slot] as Fmi2FmuState;
                // SAFETY: the buffer holds its length; a valid pointer to a handle.
                no_fatal(unsafe {
                    fmi2DeSerializeFMUstate(
                        c,
                        self.bytes.as_ptr() as *const c_char,
                        self.bytes.len(),
                        &mut s,
                    )
                });
                self.states[slot] = s as usize;
            }
            18 => {
                no_fatal(if u.arbitrary()? {
                    fmi2Reset(c)
                } else {
                    fmi2Terminate(c)
                });
            }
            _ => {
                // FMI 3.0 calls on the same handle.
                let (mut event, mut terminate, mut early, mut last) = (false, false, false, 0.0);
                let mut now = 0.0;
                // SAFETY: a valid pointer.
                let known = unsafe { fmi2GetRealStatus(c, 2, &mut now) } == 0;
                let t = if known && u.ratio(3u8, 4u8)? {
                    now
                } else {
                    float(u)?
                };
                let comm = longest_step(c) * 0.5;
                // SAFETY: valid out-pointers.
                let s = no_fatal(unsafe {
                    fmi3DoStep(
                        c,
                        t,
                        comm,
                        false,
                        &mut event,
                        &mut terminate,
                        &mut early,
                        &mut last,
                    )
                });
                if s == 0 {
                    check_step(c, t + comm);
                }
            }
        }
        Ok(())
    }
}

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let mut master = Master {
        instances: [0; SLOTS],
        states: [0; SLOTS],
        bytes: Vec::new(),
    };
    // Start with one instance, so that most calls reach one.
    let _ = master.instantiate(&mut u, false);
    for _ in 0..64 {
        if u.is_empty() || master.call(&mut u).is_err() {
            break;
        }
    }
    // Freeing the instances frees their states.
    for c in master.instances {
        fmi2FreeInstance(c as Fmi2Component);
    }
});
