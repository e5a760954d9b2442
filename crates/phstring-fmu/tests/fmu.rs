//! The FMU instance against the library's `Simulation` (bit for bit), its inputs (zero-order
//! hold of forces, ramps of positions), its error paths and its saved states; the C
//! functions in-process.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use phstring::{Material, Simulation};
use phstring_fmu::instance::{Instance, Mode, Status};
use phstring_fmu::model::{Causality, ModelSpec};
use phstring_io::scenario::parse;

/// The log of an instance: (status, message).
type Log = Arc<Mutex<Vec<(Status, String)>>>;

fn pendulum_text() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/fmu/pendulum.toml");
    std::fs::read_to_string(path).expect("examples/fmu/pendulum.toml")
}

fn spec_of(text: &str) -> ModelSpec {
    let file = parse(text, Path::new("scenario.toml"), &[]).expect("scenario parses");
    ModelSpec::new(&file).expect("scenario is valid")
}

fn instance(text: &str) -> (Instance, Log) {
    let spec = spec_of(text);
    let log: Log = Arc::default();
    let sink = log.clone();
    let inst = Instance::new(
        "test",
        &spec.guid,
        text.to_string(),
        PathBuf::from("scenario.toml"),
        Box::new(move |s, _, m| sink.lock().unwrap().push((s, m.to_string()))),
        false,
    )
    .expect("instance");
    (inst, log)
}

fn vr(inst: &Instance, name: &str) -> u32 {
    inst.spec()
        .variables
        .iter()
        .position(|v| v.name == name)
        .unwrap_or_else(|| panic!("no variable {name}")) as u32
}

fn get(inst: &mut Instance, name: &str) -> f64 {
    let r = vr(inst, name);
    let mut out = [0.0];
    assert_eq!(inst.get_real(&[r], &mut out), Status::Ok);
    out[0]
}

fn set(inst: &mut Instance, name: &str, x: f64) -> Status {
    let r = vr(inst, name);
    inst.set_real(&[r], &[x])
}

fn initialize(inst: &mut Instance) {
    assert_eq!(inst.setup_experiment(0.0, None), Status::Ok);
    assert_eq!(inst.enter_initialization(), Status::Ok);
    assert_eq!(inst.exit_initialization(), Status::Ok);
}

fn last_message(log: &Log) -> String {
    log.lock()
        .unwrap()
        .last()
        .map(|(_, m)| m.clone())
        .unwrap_or_default()
}

#[test]
fn variables_of_the_pendulum() {
    let spec = spec_of(&pendulum_text());
    let names: Vec<(&str, Causality)> = spec
        .variables
        .iter()
        .map(|v| (v.name.as_str(), v.causality))
        .collect();
    use Causality::*;
    assert_eq!(
        names,
        [
            ("EA", Parameter),
            ("rhoA", Parameter),
            ("h", Parameter),
            ("load0.F.x", Input),
            ("load0.F.y", Input),
            ("load0.v.x", Output),
            ("load0.v.y", Output),
            ("support0.R.x", Output),
            ("support0.R.y", Output),
            ("H", Output),
            ("T", Output),
            ("V", Output),
            ("supplied", Output),
            ("dissipated", Output),
            ("balance_error", Output),
            ("node30.r.x", Output),
            ("node30.r.y", Output),
        ]
    );
    // The input's start value is the pulse at t = 0; the parameters are the scenario's.
    assert_eq!(spec.variables[3].start, Some(0.0));
    assert_eq!(spec.variables[0].start, Some(20.0));
    assert_eq!(spec.variables[2].start, Some(0.01));
    // The GUID depends on the scenario.
    let other = spec_of(&pendulum_text().replace("elements = 30", "elements = 31"));
    assert_ne!(spec.guid, other.guid);
    let xml = spec.model_description("pendulum");
    assert!(xml.contains("modelIdentifier=\"pendulum\""));
    assert!(xml.contains(&format!("guid=\"{}\"", spec.guid)));
}

/// Communication step = internal step, inputs = the forces the scenario's own run applied:
/// the same Hamiltonian, bit for bit, at every step.
#[test]
fn one_internal_step_per_communication_step_is_the_run_bit_for_bit() {
    let text = pendulum_text();
    let file = parse(&text, Path::new("scenario.toml"), &[]).unwrap();
    let v = file.validate::<2>().unwrap();
    let mut sim: Simulation<2, Material> = Simulation::new(v.problem, v.settings.step).unwrap();
    let (mut inst, _) = instance(&text);
    initialize(&mut inst);
    let h = 0.01;
    let mut t = 0.0;
    for n in 0..100 {
        sim.step().unwrap();
        let u = sim.ports()[0].input;
        assert_eq!(set(&mut inst, "load0.F.x", u[0]), Status::Ok);
        assert_eq!(set(&mut inst, "load0.F.y", u[1]), Status::Ok);
        assert_eq!(inst.do_step(t, h), Status::Ok, "step {n}");
        t += h;
        let (h_fmu, h_run) = (get(&mut inst, "H"), sim.energies().hamiltonian());
        assert_eq!(
            h_fmu.to_bits(),
            h_run.to_bits(),
            "step {n}: {h_fmu} vs {h_run}"
        );
        assert_eq!(get(&mut inst, "node30.r.y"), sim.state().r[30][1]);
        assert_eq!(get(&mut inst, "load0.v.x"), sim.ports()[0].output[0]);
        assert_eq!(get(&mut inst, "support0.R.y"), sim.ports()[1].output[1]);
    }
    assert!(get(&mut inst, "balance_error").abs() <= 1e-12);
    assert!(get(&mut inst, "supplied") > 0.06);
}

/// A communication step of 3.5 internal steps lands on `t + H` exactly, holds the force,
/// and keeps the energy balance.
#[test]
fn a_communication_step_of_several_internal_steps() {
    let text = pendulum_text();
    let (mut inst, _) = instance(&text);
    initialize(&mut inst);
    assert_eq!(set(&mut inst, "load0.F.x", 0.5), Status::Ok);
    assert_eq!(set(&mut inst, "load0.F.y", 0.5), Status::Ok);
    assert_eq!(inst.do_step(0.0, 0.035), Status::Ok);
    assert_eq!(inst.time(), 0.035);
    // The same with the library: a constant load, steps of h up to 0.035 s.
    let sets = vec![
        "boundary.1.force=[\"0.5\", \"0.5\"]".to_string(),
        "boundary.1.external=false".to_string(),
    ];
    let file = parse(&text, Path::new("scenario.toml"), &sets).unwrap();
    let v = file.validate::<2>().unwrap();
    let mut sim: Simulation<2, Material> = Simulation::new(v.problem, v.settings.step).unwrap();
    while sim.time() < 0.035 - 1e-12 {
        sim.step_until(0.035).unwrap();
    }
    assert_eq!(sim.steps(), 4);
    assert_eq!(
        get(&mut inst, "H").to_bits(),
        sim.energies().hamiltonian().to_bits()
    );
    // Work of the held force: F · (r(T) − r(0)) in each component, exactly what `supplied`
    // sums step by step (h F · v_mid = F · Δr).
    let dx = get(&mut inst, "node30.r.x") - v_tip0(&text)[0];
    let dy = get(&mut inst, "node30.r.y") - v_tip0(&text)[1];
    let work = 0.5 * (dx + dy);
    assert!((get(&mut inst, "supplied") - work).abs() <= 1e-14, "{work}");
    assert!(get(&mut inst, "balance_error").abs() <= 1e-12);
}

/// The tip's initial position [m].
fn v_tip0(text: &str) -> [f64; 2] {
    let file = parse(text, Path::new("scenario.toml"), &[]).unwrap();
    let v = file.validate::<2>().unwrap();
    let r = v.problem.initial.r[30];
    [r[0], r[1]]
}

/// A 10 m steel wire (EA = 1e7 N) whose right end is an FMU input.
const WIRE: &str = r#"
dimension = 2
[geometry]
start = [0.0, 0.0]
end = [10.0, 0.0]
[mesh]
elements = 20
[material]
law = "linear_elastic"
ea = 1e7
rho_a = 0.6
[[boundary]]
node = 0
fixed = true
[[boundary]]
node = -1
position = ["10.0", "0.0"]
external = true
[time]
h = 1e-4
end = 0.1
[fmu]
nodes = [-1, 10]
"#;

/// A position input is reached at the end of the communication step, at constant speed
/// from where the support was; the balance holds with the support's power.
#[test]
fn a_position_input_is_reached_at_the_end_of_the_communication_step() {
    let (mut inst, _) = instance(WIRE);
    let names: Vec<&str> = inst
        .spec()
        .variables
        .iter()
        .filter(|v| v.causality == Causality::Input)
        .map(|v| v.name.as_str())
        .collect();
    assert_eq!(names, ["motion0.x", "motion1.y"]);
    initialize(&mut inst);
    assert_eq!(get(&mut inst, "motion0.x"), 10.0);
    assert_eq!(set(&mut inst, "motion0.x", 10.002), Status::Ok);
    assert_eq!(inst.do_step(0.0, 0.001), Status::Ok);
    assert_eq!(get(&mut inst, "node20.r.x"), 10.002);
    assert_eq!(get(&mut inst, "node20.r.y"), 0.0);
    // 2 mm in 1 ms stretches the end elements.
    // The support holds the stretched wire: it pulls the end outward (+x) [N].
    assert!(get(&mut inst, "support20.R.x") > 100.0);
    // Held: the next step does not move the support.
    assert_eq!(inst.do_step(0.001, 0.001), Status::Ok);
    assert_eq!(get(&mut inst, "node20.r.x"), 10.002);
    let (h, supplied) = (get(&mut inst, "H"), get(&mut inst, "supplied"));
    assert!(supplied > 0.0);
    assert!(
        get(&mut inst, "balance_error").abs() <= 1e-12 * h.abs().max(supplied),
        "balance {}",
        get(&mut inst, "balance_error")
    );
}

#[test]
fn bad_values_are_refused_with_their_name() {
    let (mut inst, log) = instance(&pendulum_text());
    // Each refused value is named and not taken; FMI's error state follows (no further
    // set), and reset starts over.
    for (name, x, needle) in [
        ("EA", -1.0, "EA = -1"),
        ("load0.F.x", f64::NAN, "load0.F.x"),
        ("H", 1.0, "output"),
    ] {
        assert_eq!(set(&mut inst, name, x), Status::Error, "{name}");
        let m = last_message(&log);
        assert!(m.contains(needle) && m.contains("error state"), "{m}");
        assert_eq!(inst.mode(), Mode::Error);
        assert_eq!(
            set(&mut inst, "EA", 30.0),
            Status::Error,
            "no set after an error"
        );
        assert_eq!(inst.reset(), Status::Ok);
        assert_eq!(get(&mut inst, "EA"), 20.0);
        assert_eq!(get(&mut inst, "load0.F.x"), 0.0);
    }
    assert_eq!(inst.set_real(&[999], &[1.0]), Status::Error);
    assert!(last_message(&log).contains("999"));
    assert_eq!(inst.reset(), Status::Ok);
    // A value that is positive but does not fit the scenario: refused when the simulation
    // is set up, with the scenario's message.
    assert_eq!(set(&mut inst, "h", 1e-300), Status::Ok);
    assert_eq!(inst.setup_experiment(0.0, Some(1.0)), Status::Ok);
    assert_eq!(inst.enter_initialization(), Status::Ok);
    assert_eq!(inst.exit_initialization(), Status::Error);
    let m = last_message(&log);
    assert!(m.contains("time.h") && m.contains("1e10"), "{m}");
    assert_eq!(inst.mode(), Mode::Error);
    // Reset starts over with the start values.
    assert_eq!(inst.reset(), Status::Ok);
    initialize(&mut inst);
    assert_eq!(get(&mut inst, "h"), 0.01);
    // A changed parameter takes effect: a heavier string has more (negative) potential.
    let (mut heavy, heavy_log) = instance(&pendulum_text());
    assert_eq!(set(&mut heavy, "rhoA", 2.0), Status::Ok);
    initialize(&mut heavy);
    let ratio = get(&mut heavy, "V") / get(&mut inst, "V");
    assert!((ratio - 2.0).abs() < 1e-12, "{ratio}");
    // After initialization a fixed parameter cannot change.
    assert_eq!(set(&mut heavy, "rhoA", 3.0), Status::Error);
    assert!(last_message(&heavy_log).contains("fixed parameter"));
    assert_eq!(get(&mut heavy, "rhoA"), 2.0);
}

#[test]
fn calls_out_of_order_are_refused() {
    let (mut inst, log) = instance(&pendulum_text());
    assert_eq!(inst.do_step(0.0, 0.01), Status::Error);
    assert!(last_message(&log).contains("fmi2DoStep"));
    assert_eq!(inst.mode(), Mode::Error);
    assert_eq!(inst.reset(), Status::Ok);
    assert_eq!(inst.setup_experiment(0.0, Some(0.05)), Status::Ok);
    assert_eq!(inst.enter_initialization(), Status::Ok);
    assert_eq!(inst.exit_initialization(), Status::Ok);
    let saved = inst.save().unwrap();
    for (t, comm_h, needle) in [
        (0.5, 0.01, "the FMU is at t = 0 s"),
        (0.0, -0.01, "positive and finite"),
        (0.0, f64::NAN, "positive and finite"),
        (f64::NAN, 0.01, "currentCommunicationPoint = NaN"),
        (0.0, 0.06, "stopTime"),
    ] {
        assert_eq!(inst.do_step(t, comm_h), Status::Error, "{t}, {comm_h}");
        assert!(
            last_message(&log).contains(needle),
            "{}",
            last_message(&log)
        );
        // FMI's error state: no step until a saved state is restored.
        assert_eq!(inst.do_step(0.0, 0.01), Status::Error);
        assert_eq!(inst.restore(&saved), Status::Ok);
    }
    // None of these changed anything.
    assert_eq!(inst.do_step(0.0, 0.04), Status::Ok);
    assert_eq!(inst.time(), 0.04);
    assert_eq!(inst.terminate(), Status::Ok);
    assert_eq!(inst.terminate(), Status::Error);
    assert_eq!(inst.do_step(0.05, 0.01), Status::Error);
}

/// A step that cannot converge is discarded: the FMU stays at the last step it completed,
/// says why, and continues from a saved state.
#[test]
fn a_diverging_step_is_discarded_and_a_saved_state_continues() {
    let (mut inst, log) = instance(&pendulum_text());
    initialize(&mut inst);
    assert_eq!(inst.do_step(0.0, 0.02), Status::Ok);
    let saved = inst.save().unwrap();
    assert_eq!(set(&mut inst, "load0.F.x", 1e160), Status::Ok);
    assert_eq!(inst.do_step(0.02, 0.01), Status::Discard);
    assert_eq!(inst.mode(), Mode::StepFailed);
    assert_eq!(inst.time(), 0.02);
    let m = last_message(&log);
    assert!(m.contains("step 3") && m.contains("t = 0.02 s"), "{m}");
    assert_eq!(inst.do_step(0.02, 0.01), Status::Error);
    assert_eq!(set(&mut inst, "load0.F.x", 0.0), Status::Error);
    assert!(last_message(&log).contains("fmi2SetFMUstate"));
    assert_eq!(inst.restore(&saved), Status::Ok);
    assert_eq!(inst.mode(), Mode::StepComplete);
    assert_eq!(get(&mut inst, "load0.F.x"), 0.0);
    assert_eq!(inst.do_step(0.02, 0.01), Status::Ok);
}

/// Saving, continuing, restoring and continuing again gives the same run bit for bit, also
/// in another instance and through the JSON form.
#[test]
fn saved_states_continue_bit_for_bit() {
    let text = pendulum_text();
    let (mut a, _) = instance(&text);
    initialize(&mut a);
    let h = 0.01;
    let pulse = |t: f64| (std::f64::consts::PI * (t + 0.5 * h) / 0.2).sin() * 0.5;
    let run = |inst: &mut Instance, from: usize, to: usize| -> Vec<u64> {
        (from..to)
            .map(|n| {
                let t = n as f64 * h;
                set(inst, "load0.F.x", pulse(t));
                set(inst, "load0.F.y", pulse(t));
                assert_eq!(inst.do_step(t, h), Status::Ok);
                get(inst, "H").to_bits()
            })
            .collect()
    };
    run(&mut a, 0, 15);
    let saved = a.save().unwrap();
    let first = run(&mut a, 15, 40);
    assert_eq!(a.restore(&saved), Status::Ok);
    assert_eq!(run(&mut a, 15, 40), first);
    let json = serde_json::to_string(&saved).unwrap();
    let back = serde_json::from_str(&json).unwrap();
    let (mut b, _) = instance(&text);
    initialize(&mut b);
    assert_eq!(b.restore(&back), Status::Ok);
    assert_eq!(b.time(), 14.0 * h + h, "the master's clock after step 15");
    assert_eq!(run(&mut b, 15, 40), first);
}

#[test]
fn a_guid_of_another_scenario_is_refused() {
    let text = pendulum_text();
    let other = spec_of(&text.replace("ea = 20.0", "ea = 21.0"));
    let err = Instance::new(
        "x",
        &other.guid,
        text,
        PathBuf::from("scenario.toml"),
        Box::new(|_, _, _| {}),
        false,
    )
    .err()
    .expect("refused")
    .to_string();
    assert!(err.contains("GUID"), "{err}");
}

mod c_functions {
    //! The FMI C functions, called as a master would (without a logger).
    #![allow(unsafe_code)]

    use super::*;
    use phstring_fmu::ffi::*;
    use std::ffi::CString;

    #[test]
    fn resource_uris_decode() {
        assert_eq!(
            resource_dir("file:///tmp/my%20fmu/resources").unwrap(),
            PathBuf::from("/tmp/my fmu/resources")
        );
        assert_eq!(
            resource_dir("file:/tmp/r").unwrap(),
            PathBuf::from("/tmp/r")
        );
        assert_eq!(
            resource_dir("file://localhost/tmp/r%").unwrap(),
            PathBuf::from("/tmp/r%")
        );
        assert!(resource_dir("http://example.org/r").is_err());
    }

    #[test]
    fn a_master_s_calls() {
        let text = pendulum_text();
        let spec = spec_of(&text);
        let dir = tempfile::tempdir().unwrap();
        let resources = dir.path().join("with space").join("resources");
        std::fs::create_dir_all(&resources).unwrap();
        std::fs::write(resources.join("scenario.toml"), &text).unwrap();
        let uri = format!(
            "file://{}",
            resources.display().to_string().replace(' ', "%20")
        );
        let (name, uri) = (CString::new("c").unwrap(), CString::new(uri).unwrap());
        let guid = CString::new(spec.guid.clone()).unwrap();
        let h_vr = spec.variables.iter().position(|v| v.name == "H").unwrap() as u32;
        let fx_vr = spec
            .variables
            .iter()
            .position(|v| v.name == "load0.F.x")
            .unwrap() as u32;
        unsafe {
            let wrong = CString::new("{00000000-0000-0000-0000-000000000000}").unwrap();
            let none = fmi2Instantiate(
                name.as_ptr(),
                1,
                wrong.as_ptr(),
                uri.as_ptr(),
                std::ptr::null(),
                0,
                0,
            );
            assert!(none.is_null());
            let c = fmi2Instantiate(
                name.as_ptr(),
                1,
                guid.as_ptr(),
                uri.as_ptr(),
                std::ptr::null(),
                0,
                0,
            );
            assert!(!c.is_null());
            assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 1, 1.0), 0);
            assert_eq!(fmi2EnterInitializationMode(c), 0);
            assert_eq!(fmi2ExitInitializationMode(c), 0);
            assert_eq!(fmi2SetReal(c, &fx_vr, 1, &0.3), 0);
            assert_eq!(fmi2DoStep(c, 0.0, 0.05, 1), 0);
            let mut state: Fmi2FmuState = std::ptr::null_mut();
            assert_eq!(fmi2GetFMUstate(c, &mut state), 0);
            let mut size = 0usize;
            assert_eq!(fmi2SerializedFMUstateSize(c, state, &mut size), 0);
            let mut bytes = vec![0 as std::ffi::c_char; size];
            assert_eq!(fmi2SerializeFMUstate(c, state, bytes.as_mut_ptr(), size), 0);
            let mut h_then = 0.0;
            assert_eq!(fmi2GetReal(c, &h_vr, 1, &mut h_then), 0);
            assert_eq!(fmi2DoStep(c, 0.05, 0.05, 1), 0);
            let mut copy: Fmi2FmuState = std::ptr::null_mut();
            assert_eq!(
                fmi2DeSerializeFMUstate(c, bytes.as_ptr(), size, &mut copy),
                0
            );
            assert_eq!(fmi2SetFMUstate(c, copy), 0);
            let mut h_back = 0.0;
            assert_eq!(fmi2GetReal(c, &h_vr, 1, &mut h_back), 0);
            assert_eq!(h_back.to_bits(), h_then.to_bits());
            let mut t = 0.0;
            assert_eq!(fmi2GetRealStatus(c, 2, &mut t), 0);
            assert_eq!(t, 0.05);
            assert_eq!(fmi2Terminate(c), 0);
            // Null arrays and other types are errors (FMI's error state follows), not crashes.
            assert_eq!(fmi2GetReal(c, std::ptr::null(), 1, &mut h_back), 3);
            assert_eq!(fmi2GetInteger(c, &h_vr, 1, std::ptr::null_mut()), 3);
            assert_eq!(fmi2DoStep(std::ptr::null_mut(), 0.0, 0.1, 1), 3);
            assert_eq!(fmi2FreeFMUstate(c, &mut state), 0);
            assert_eq!(fmi2FreeFMUstate(c, &mut copy), 0);
            assert!(state.is_null() && copy.is_null());
            fmi2FreeInstance(c);
        }
    }
}

/// The mooring line (160 m steel rope from its static equilibrium) with the fairlead's
/// heave as the FMU's position inputs, set to where a run with the heave's sine has the
/// support at the end of each step: the FMU is, bit for bit, the library driven by the same
/// straight ramps from one communication point to the next (its support's velocity is the
/// ramp's, not the sine's, so it is not the sine's run bit for bit).
#[test]
fn a_moving_support_from_the_master_is_the_run_bit_for_bit() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/slack_wire.toml");
    let sets = [
        "boundary.1.external=true".to_string(),
        // The heave without the example's build-up, so that it moves from the start.
        r#"boundary.1.position=["120", "60 + 1.0 * sin(2*pi*t/10)"]"#.to_string(),
        "fmu.nodes=[-1, 80]".to_string(),
        "time.end=0.5".to_string(),
        // At h = 0.01 s the run halves a step as the line goes slack near the anchor, and a
        // half step samples the heave's sine where the FMU's ramp is straight.
        "time.h=0.005".to_string(),
    ];
    let file = phstring_io::scenario::load(&path, &sets).unwrap();
    let text = file.text().to_string();
    let mut v = file.validate::<2>().unwrap();
    let phstring::ByDim::D2(setup) = file.setup().unwrap() else {
        panic!("the mooring line is 2D")
    };
    let eq = setup.equilibrium(false, None).unwrap();
    v.problem.initial = v.initial_state(&eq.state.r).unwrap();
    let mut sine: Simulation<2, Material> =
        Simulation::new(v.problem.clone(), v.settings.step).unwrap();
    // The same line, its fairlead on ramps from the last target to the next over each step.
    type Ramp = Arc<Mutex<(f64, f64, f64, f64)>>;
    let ramp_of = |m: &mut phstring::Motion| -> Ramp {
        let x0 = (m.position)(0.0);
        let ramp: Ramp = Arc::new(Mutex::new((0.0, 0.0, x0, x0)));
        let r = ramp.clone();
        m.position = Arc::new(move |t| {
            let (t0, t1, from, to) = *r.lock().unwrap();
            if t >= t1 - 1e-9 * (t1 - t0) {
                to
            } else if t <= t0 {
                from
            } else {
                from + (to - from) * ((t - t0) / (t1 - t0))
            }
        });
        ramp
    };
    let mut problem = v.problem;
    let ramps: Vec<Ramp> = problem.boundary.motions.iter_mut().map(ramp_of).collect();
    let mut ramped: Simulation<2, Material> = Simulation::new(problem, v.settings.step).unwrap();
    let (mut inst, _) = instance(&text);
    initialize(&mut inst);
    // Both start at the equilibrium, at rest.
    assert_eq!(get(&mut inst, "node80.r.y"), ramped.state().r[80][1]);
    assert_eq!(get(&mut inst, "T"), 0.0);
    let h = 0.005;
    for n in 0..100 {
        assert_eq!(sine.step().unwrap().rejected, 0);
        let fairlead = sine.state().r[160];
        let (t0, t1) = (n as f64 * h, (n + 1) as f64 * h);
        for (ramp, to) in ramps.iter().zip([fairlead[0], fairlead[1]]) {
            let mut r = ramp.lock().unwrap();
            *r = (t0, t1, r.3, to);
        }
        assert_eq!(ramped.step().unwrap().rejected, 0);
        assert_eq!(set(&mut inst, "motion0.x", fairlead[0]), Status::Ok);
        assert_eq!(set(&mut inst, "motion1.y", fairlead[1]), Status::Ok);
        assert_eq!(inst.do_step(t0, h), Status::Ok);
        assert_eq!(
            get(&mut inst, "H").to_bits(),
            ramped.energies().hamiltonian().to_bits(),
            "step {n}"
        );
        assert_eq!(get(&mut inst, "node160.r.y"), fairlead[1]);
        assert_eq!(
            get(&mut inst, "support160.R.y"),
            ramped.ports()[1].output[1]
        );
    }
    // The heave did work on the line (0.3 m up in 0.5 s against a tension of ~1e5 N).
    assert!(get(&mut inst, "supplied").abs() > 1e3);
    assert!(get(&mut inst, "balance_error").abs() <= 1e-12 * get(&mut inst, "H").abs());
}

/// Port outputs after `fmi2SetFMUstate` are those of the saved point (also in a fresh
/// instance); a state that cannot be restored changes nothing.
#[test]
fn restored_states_report_their_own_port_outputs_and_a_failed_restore_changes_nothing() {
    let text = pendulum_text();
    let (mut a, log) = instance(&text);
    initialize(&mut a);
    set(&mut a, "load0.F.x", 0.4);
    assert_eq!(a.do_step(0.0, 0.05), Status::Ok);
    let names = [
        "load0.v.x",
        "load0.v.y",
        "support0.R.x",
        "support0.R.y",
        "H",
    ];
    let at_save: Vec<f64> = names.iter().map(|n| get(&mut a, n)).collect();
    let saved = a.save().unwrap();
    assert_eq!(a.do_step(0.05, 0.05), Status::Ok);
    assert_ne!(get(&mut a, "load0.v.x"), at_save[0]);
    assert_eq!(a.restore(&saved), Status::Ok);
    let back: Vec<f64> = names.iter().map(|n| get(&mut a, n)).collect();
    assert_eq!(back, at_save);
    let json: phstring_fmu::instance::Saved =
        serde_json::from_str(&serde_json::to_string(&saved).unwrap()).unwrap();
    let (mut b, _) = instance(&text);
    initialize(&mut b);
    assert_eq!(b.restore(&json), Status::Ok);
    let fresh: Vec<f64> = names.iter().map(|n| get(&mut b, n)).collect();
    assert_eq!(fresh, at_save);
    // A state of another mesh (same variables, 31 elements): refused, nothing changed.
    let other_text = text.replace("elements = 30", "elements = 31");
    let (mut other, _) = instance(&other_text);
    initialize(&mut other);
    assert_eq!(other.do_step(0.0, 0.03), Status::Ok);
    let foreign = other.save().unwrap();
    assert_eq!(a.do_step(0.05, 0.02), Status::Ok);
    let (t, h) = (a.time(), get(&mut a, "H"));
    assert_eq!(a.restore(&foreign), Status::Error);
    assert!(
        last_message(&log).contains("another FMU"),
        "{}",
        last_message(&log)
    );
    assert_eq!((a.time(), get(&mut a, "H")), (t, h));
    // A state of this FMU whose parameters do not set up (h = 1e-300, edited in its JSON):
    // the new simulation cannot be built, and the running one is kept.
    let mut edited: serde_json::Value = serde_json::to_value(&saved).unwrap();
    edited["values"][2] = serde_json::json!(1e-300);
    let edited: phstring_fmu::instance::Saved = serde_json::from_value(edited).unwrap();
    assert_eq!(a.restore(&edited), Status::Error);
    assert!(
        last_message(&log).contains("time.h"),
        "{}",
        last_message(&log)
    );
    assert_eq!((a.time(), get(&mut a, "H")), (t, h));
    assert_eq!(get(&mut a, "h"), 0.01);
    // A refused restore is an fmi2Error: the error state, left by restoring a good state.
    assert_eq!(a.mode(), Mode::Error);
    assert_eq!(a.do_step(t, 0.01), Status::Error);
    assert_eq!(a.restore(&saved), Status::Ok);
    assert_eq!(a.do_step(0.05, 0.01), Status::Ok);
}

/// With `initial.equilibrium`, the start is the equilibrium under the load inputs set in
/// initialization; a saved state carries its `Ĥ(0)`, so the balance is the same after a
/// restore into a fresh instance (which does not solve for the equilibrium again).
#[test]
fn the_balance_survives_a_restore_of_a_run_from_its_equilibrium() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/fmu/hoist.toml");
    let file =
        phstring_io::scenario::load(&path, &["initial.equilibrium=true".to_string()]).unwrap();
    let text = file.text().to_string();
    let (mut a, _) = instance(&text);
    assert_eq!(a.setup_experiment(0.0, None), Status::Ok);
    assert_eq!(a.enter_initialization(), Status::Ok);
    assert_eq!(set(&mut a, "load0.F.x", 500.0), Status::Ok);
    assert_eq!(a.exit_initialization(), Status::Ok);
    // At rest at the start: the payload hangs pulled aside by the 500 N.
    assert_eq!(get(&mut a, "T"), 0.0);
    let x0 = get(&mut a, "node20.r.x");
    assert!(x0 > 0.1, "{x0}");
    for n in 0..10 {
        set(&mut a, "load0.F.x", 500.0 + 100.0 * n as f64);
        assert_eq!(a.do_step(n as f64 * 0.01, 0.01), Status::Ok);
    }
    let balance = get(&mut a, "balance_error");
    assert!(balance.abs() <= 1e-9, "{balance}");
    let saved = a.save().unwrap();
    let (mut b, _) = instance(&text);
    initialize(&mut b);
    assert_eq!(b.restore(&saved), Status::Ok);
    assert_eq!(get(&mut b, "balance_error").to_bits(), balance.to_bits());
    for inst in [&mut a, &mut b] {
        set(inst, "load0.F.x", 2000.0);
        assert_eq!(inst.do_step(0.1, 0.01), Status::Ok);
    }
    assert_eq!(
        get(&mut a, "balance_error").to_bits(),
        get(&mut b, "balance_error").to_bits()
    );
    assert_eq!(get(&mut a, "H").to_bits(), get(&mut b, "H").to_bits());
}

mod fmi3_functions {
    //! The FMI 3.0 functions of the same library, called as a master would.
    #![allow(unsafe_code)]

    use super::*;
    use phstring_fmu::ffi3::*;
    use std::ffi::CString;

    #[test]
    fn a_master_s_calls() {
        let text = pendulum_text();
        let spec = spec_of(&text);
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("scenario.toml"), &text).unwrap();
        let resources = CString::new(format!("{}/", dir.path().display())).unwrap();
        let name = CString::new("c3").unwrap();
        let token = CString::new(spec.guid.clone()).unwrap();
        let vr = |n: &str| spec.variables.iter().position(|v| v.name == n).unwrap() as u32;
        let (h_vr, fx_vr, time_vr) = (vr("H"), vr("load0.F.x"), spec.time_reference());
        unsafe {
            let instantiate = |token: &CString| {
                fmi3InstantiateCoSimulation(
                    name.as_ptr(),
                    token.as_ptr(),
                    resources.as_ptr(),
                    false,
                    false,
                    false,
                    false,
                    std::ptr::null(),
                    0,
                    std::ptr::null_mut(),
                    None,
                    std::ptr::null(),
                )
            };
            let c = instantiate(&token);
            assert!(!c.is_null());
            assert_eq!(
                fmi3EnterInitializationMode(c, false, 0.0, 0.0, true, 1.0),
                0
            );
            assert_eq!(fmi3ExitInitializationMode(c), 0);
            assert_eq!(fmi3SetFloat64(c, &fx_vr, 1, &0.3, 1), 0);
            let (mut event, mut terminate, mut early, mut last) = (true, true, true, 0.0);
            assert_eq!(
                fmi3DoStep(
                    c,
                    0.0,
                    0.05,
                    false,
                    &mut event,
                    &mut terminate,
                    &mut early,
                    &mut last
                ),
                0
            );
            assert_eq!((event, terminate, early, last), (false, false, false, 0.05));
            let mut t = 0.0;
            assert_eq!(fmi3GetFloat64(c, &time_vr, 1, &mut t, 1), 0);
            assert_eq!(t, 0.05);
            let mut state: Fmi3FmuState = std::ptr::null_mut();
            assert_eq!(fmi3GetFMUState(c, &mut state), 0);
            let mut size = 0usize;
            assert_eq!(fmi3SerializedFMUStateSize(c, state, &mut size), 0);
            let mut bytes = vec![0u8; size];
            assert_eq!(fmi3SerializeFMUState(c, state, bytes.as_mut_ptr(), size), 0);
            let mut h_then = 0.0;
            assert_eq!(fmi3GetFloat64(c, &h_vr, 1, &mut h_then, 1), 0);
            assert_eq!(
                fmi3DoStep(
                    c,
                    0.05,
                    0.05,
                    false,
                    &mut event,
                    &mut terminate,
                    &mut early,
                    &mut last
                ),
                0
            );
            let mut copy: Fmi3FmuState = std::ptr::null_mut();
            assert_eq!(
                fmi3DeserializeFMUState(c, bytes.as_ptr(), size, &mut copy),
                0
            );
            assert_eq!(fmi3SetFMUState(c, copy), 0);
            let mut h_back = 0.0;
            assert_eq!(fmi3GetFloat64(c, &h_vr, 1, &mut h_back, 1), 0);
            assert_eq!(h_back.to_bits(), h_then.to_bits());
            // A diverging step: discarded, with terminateSimulation and the last time.
            assert_eq!(fmi3SetFloat64(c, &fx_vr, 1, &1e160, 1), 0);
            assert_eq!(
                fmi3DoStep(
                    c,
                    0.05,
                    0.01,
                    false,
                    &mut event,
                    &mut terminate,
                    &mut early,
                    &mut last
                ),
                2
            );
            assert!(terminate);
            assert_eq!(last, 0.05);
            assert_eq!(fmi3Terminate(c), 0);
            assert_eq!(
                fmi3SetFloat64(c, &time_vr, 1, &0.3, 1),
                3,
                "time cannot be set"
            );
            // What the FMU does not declare is refused, not a crash.
            assert_eq!(fmi3EnterEventMode(c), 3);
            let mut n = 0usize;
            assert_eq!(fmi3GetNumberOfContinuousStates(c, &mut n), 3);
            let mut i = 0i32;
            assert_eq!(fmi3GetInt32(c, &h_vr, 1, &mut i, 1), 3);
            assert_eq!(
                fmi3GetInt32(c, std::ptr::null(), 0, std::ptr::null_mut(), 0),
                0
            );
            let mut two = [0.0; 2];
            assert_eq!(fmi3GetFloat64(c, &h_vr, 1, two.as_mut_ptr(), 2), 3);
            assert_eq!(fmi3FreeFMUState(c, &mut state), 0);
            assert_eq!(fmi3FreeFMUState(c, &mut copy), 0);
            fmi3FreeInstance(c);
            // A wrong token is refused.
            let wrong = CString::new("{x}").unwrap();
            let none = instantiate(&wrong);
            assert!(none.is_null());
        }
    }
}

/// The fourth-order scheme and error control run inside the FMU as in the library stepping
/// to the same communication points: the same `Ĥ`, bit for bit, and the balance.
#[test]
fn dg4_and_error_control_inside_the_fmu() {
    for extra in [
        vec!["time.scheme=\"dg4\""],
        vec!["time.rtol=1e-5", "time.atol=1e-5"],
    ] {
        let sets: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
        let base = parse(&pendulum_text(), Path::new("scenario.toml"), &sets).unwrap();
        let text = base.text().to_string();
        let (mut inst, _) = instance(&text);
        initialize(&mut inst);
        let mut with_load = sets.clone();
        with_load.push("boundary.1.force=[\"0.2\", \"0.1\"]".into());
        let file = parse(&pendulum_text(), Path::new("scenario.toml"), &with_load).unwrap();
        let v = file.validate::<2>().unwrap();
        let mut sim: Simulation<2, Material> = Simulation::new(v.problem, v.settings.step).unwrap();
        let comm = 0.05;
        for n in 0..8 {
            set(&mut inst, "load0.F.x", 0.2);
            set(&mut inst, "load0.F.y", 0.1);
            assert_eq!(inst.do_step(n as f64 * comm, comm), Status::Ok, "{extra:?}");
            // The target as the FMU computes it from the master's t and H (not (n + 1) H,
            // which may differ in the last bit and, with error control, shift the steps).
            let target = n as f64 * comm + comm;
            while sim.time() < target - 1e-9 * 0.01 {
                sim.step_until(target).unwrap();
            }
            assert_eq!(
                get(&mut inst, "H").to_bits(),
                sim.energies().hamiltonian().to_bits(),
                "{extra:?} at communication step {n}"
            );
        }
        assert!(get(&mut inst, "balance_error").abs() <= 1e-12, "{extra:?}");
    }
}

/// The hoist (a 10 m rope with a 200 kg payload released at 20°) from rest with the
/// parameter `h`: every `fmi2DoStep` that returns `Ok` has moved the model to the master's
/// time (the payload gained kinetic energy), however large `h` is.
#[test]
fn a_huge_internal_step_moves_the_model_or_fails_never_a_silent_ok() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/fmu/hoist.toml");
    let text = std::fs::read_to_string(path).unwrap();
    // 20 s steps: each 0.5 s communication step is one internal step of 0.5 s.
    for h in [1e10, 2e9, 20.0] {
        let (mut inst, log) = instance(&text);
        assert_eq!(inst.setup_experiment(0.0, None), Status::Ok);
        assert_eq!(inst.enter_initialization(), Status::Ok);
        assert_eq!(set(&mut inst, "h", h), Status::Ok);
        assert_eq!(inst.exit_initialization(), Status::Ok);
        let x0 = get(&mut inst, "node20.r.x");
        assert_eq!(get(&mut inst, "T"), 0.0);
        let comm = 0.5;
        let mut t = 0.0;
        for k in 0..3 {
            match inst.do_step(t, comm) {
                Status::Ok => {
                    t += comm;
                    // Released from rest: any step taken moves the payload.
                    assert!(get(&mut inst, "T") > 1.0, "h = {h}, step {k}: T = 0");
                    assert_ne!(get(&mut inst, "node20.r.x"), x0);
                }
                Status::Discard => {
                    // The FMU says where it stopped: the last step it completed.
                    assert_eq!(inst.time(), t);
                    assert!(last_message(&log).contains(&format!("stays at t = {t} s")));
                    break;
                }
                s => panic!("h = {h}, step {k}: {s:?}: {}", last_message(&log)),
            }
        }
        assert!(get(&mut inst, "balance_error").abs() <= 1e-6 * get(&mut inst, "H").abs());
    }
}

/// With a stop time, an internal step longer than the whole experiment is refused when
/// initialization ends, naming `h`.
#[test]
fn an_internal_step_longer_than_the_experiment_is_refused() {
    let (mut inst, log) = instance(&pendulum_text());
    assert_eq!(inst.setup_experiment(0.0, Some(1.5)), Status::Ok);
    assert_eq!(inst.enter_initialization(), Status::Ok);
    assert_eq!(set(&mut inst, "h", 1e10), Status::Ok);
    assert_eq!(inst.exit_initialization(), Status::Error);
    let m = last_message(&log);
    assert!(
        m.contains("parameter h = 10000000000 s") && m.contains("stopTime = 1.5 s"),
        "{m}"
    );
    assert_eq!(inst.mode(), Mode::Error);
    // h equal to the experiment (rounding of stop − start included) is accepted.
    let (mut inst, _) = instance(&pendulum_text());
    assert_eq!(inst.setup_experiment(0.1, Some(0.3)), Status::Ok);
    assert_eq!(inst.enter_initialization(), Status::Ok);
    assert_eq!(set(&mut inst, "h", 0.2), Status::Ok);
    assert_eq!(inst.exit_initialization(), Status::Ok);
    assert_eq!(inst.do_step(0.1, 0.2), Status::Ok);
    assert!(get(&mut inst, "T") > 0.0);
}

/// At `startTime = 1e17` the master's clock cannot advance by 0.01 s (`t + H == t`), nor
/// meaningfully by 20 s (the doubles there are 16 s apart): `fmi2Error`, not a step that
/// reports success without moving.
#[test]
fn a_step_below_the_resolution_of_t_is_an_error() {
    for (start, comm) in [(1e17, 0.01), (1e17, 20.0), (1e300, 1.0)] {
        let (mut inst, log) = instance(&pendulum_text());
        assert_eq!(inst.setup_experiment(start, None), Status::Ok);
        assert_eq!(inst.enter_initialization(), Status::Ok);
        assert_eq!(inst.exit_initialization(), Status::Ok);
        let x = get(&mut inst, "node30.r.x");
        assert_eq!(inst.do_step(start, comm), Status::Error, "{start}, {comm}");
        let m = last_message(&log);
        assert!(m.contains("below the resolution"), "{m}");
        assert_eq!(inst.mode(), Mode::Error);
        assert_eq!(inst.time(), start);
        assert_eq!(get(&mut inst, "node30.r.x"), x);
        assert_eq!(inst.do_step(start, 1e20), Status::Error, "the error state");
    }
}

/// A communication step far shorter than `h` is one internal step of that length (the
/// landing tolerance scales with the step asked for): the model moves, the balance holds.
#[test]
fn a_communication_step_far_below_h_is_taken() {
    let (mut inst, _) = instance(&pendulum_text());
    initialize(&mut inst);
    assert_eq!(inst.do_step(0.0, 0.04), Status::Ok);
    let h_before = get(&mut inst, "H");
    let saved = inst.save().unwrap();
    assert_eq!(inst.do_step(0.04, 1e-15), Status::Ok);
    assert_eq!(inst.time(), 0.04 + 1e-15);
    assert_eq!(inst.do_step(0.04 + 1e-15, 0.01 - 1e-15), Status::Ok);
    let after = get(&mut inst, "H");
    assert!((after - h_before).abs() <= 1e-12, "{after} vs {h_before}");
    assert!(get(&mut inst, "balance_error").abs() <= 1e-12);
    // Against one step of 0.01 s from the same state: the same motion, up to the split.
    let split = get(&mut inst, "node30.r.y");
    assert_eq!(inst.restore(&saved), Status::Ok);
    assert_eq!(inst.do_step(0.04, 0.01), Status::Ok);
    let whole = get(&mut inst, "node30.r.y");
    assert!((split - whole).abs() <= 1e-6, "{split} vs {whole}");
}

/// FMI's error state: after any `fmi2Error` only getters, a restore, reset and free are
/// accepted; a non-finite start time is one.
#[test]
fn after_an_error_only_getters_restore_reset_and_free_are_accepted() {
    let (mut inst, log) = instance(&pendulum_text());
    assert_eq!(inst.setup_experiment(f64::NAN, None), Status::Error);
    assert!(last_message(&log).contains("startTime"));
    assert_eq!(inst.mode(), Mode::Error);
    assert_eq!(inst.setup_experiment(0.0, None), Status::Error);
    assert_eq!(inst.enter_initialization(), Status::Error);
    assert_eq!(set(&mut inst, "EA", 30.0), Status::Error);
    assert_eq!(get(&mut inst, "EA"), 20.0, "getters still answer");
    assert!(inst.save().is_err(), "no state is saved in the error state");
    assert_eq!(inst.reset(), Status::Ok);
    initialize(&mut inst);
    let saved = inst.save().unwrap();
    // A refused input while stepping: the next step is refused until a restore, which
    // brings back the input as saved.
    assert_eq!(set(&mut inst, "load0.F.x", f64::INFINITY), Status::Error);
    assert_eq!(inst.do_step(0.0, 0.01), Status::Error);
    assert_eq!(inst.restore(&saved), Status::Ok);
    assert_eq!(get(&mut inst, "load0.F.x"), 0.0);
    assert_eq!(inst.do_step(0.0, 0.01), Status::Ok);
}

/// A serialized state carries a checksum: an edited value is refused with a clear message,
/// the unedited bytes restore.
#[test]
fn an_edited_serialized_state_is_refused() {
    use phstring_fmu::instance::Saved;
    let (mut inst, _) = instance(&pendulum_text());
    initialize(&mut inst);
    assert_eq!(set(&mut inst, "load0.F.x", 0.3), Status::Ok);
    assert_eq!(inst.do_step(0.0, 0.05), Status::Ok);
    let bytes = inst.save().unwrap().to_bytes().unwrap();
    let text = String::from_utf8(bytes.clone()).unwrap();
    // Node 0's x (the fixed end, at 0.0) moved to 7.0.
    let at = text.find("\"r\":[").expect("positions") + 5;
    assert_eq!(&text[at..at + 4], "0.0,");
    let edited = format!("{}7{}", &text[..at], &text[at + 1..]);
    let err = Saved::from_bytes(edited.as_bytes())
        .expect_err("refused")
        .to_string();
    assert!(err.contains("checksum mismatch"), "{err}");
    for bad in [&bytes[..bytes.len() / 2], b"{}", b""] {
        let err = Saved::from_bytes(bad).expect_err("refused").to_string();
        assert!(err.contains("not a serialized state"), "{err}");
    }
    let back = Saved::from_bytes(&bytes).unwrap();
    assert_eq!(inst.do_step(0.05, 0.05), Status::Ok);
    assert_eq!(inst.restore(&back), Status::Ok);
    assert_eq!(inst.time(), 0.05);
}

mod handles_and_threads {
    //! The C functions' handles: freed instances and states are refused, not dereferenced;
    //! calls on one instance from many threads run one at a time.
    #![allow(unsafe_code)]

    use super::*;
    use phstring_fmu::ffi::*;
    use std::ffi::CString;

    /// An instance of the pendulum through `fmi2Instantiate`, in initialization-complete
    /// state at t = 0, with its folder (kept alive by the caller).
    fn pendulum_instance() -> (Fmi2Component, tempfile::TempDir, ModelSpec) {
        let text = pendulum_text();
        let spec = spec_of(&text);
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("scenario.toml"), &text).unwrap();
        let uri = CString::new(format!("file://{}", dir.path().display())).unwrap();
        let (name, guid) = (
            CString::new("t").unwrap(),
            CString::new(spec.guid.clone()).unwrap(),
        );
        unsafe {
            let c = fmi2Instantiate(
                name.as_ptr(),
                1,
                guid.as_ptr(),
                uri.as_ptr(),
                std::ptr::null(),
                0,
                0,
            );
            assert!(!c.is_null());
            assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), 0);
            assert_eq!(fmi2EnterInitializationMode(c), 0);
            assert_eq!(fmi2ExitInitializationMode(c), 0);
            (c, dir, spec)
        }
    }

    fn vr_of(spec: &ModelSpec, name: &str) -> u32 {
        spec.variables.iter().position(|v| v.name == name).unwrap() as u32
    }

    #[test]
    fn a_freed_instance_or_state_is_refused_not_a_crash() {
        let (c, _dir, spec) = pendulum_instance();
        let h_vr = vr_of(&spec, "H");
        unsafe {
            assert_eq!(fmi2DoStep(c, 0.0, 0.01, 1), 0);
            let mut state: Fmi2FmuState = std::ptr::null_mut();
            assert_eq!(fmi2GetFMUstate(c, &mut state), 0);
            let stale = state;
            assert_eq!(fmi2FreeFMUstate(c, &mut state), 0);
            assert!(state.is_null());
            assert_eq!(fmi2SetFMUstate(c, stale), 3, "a freed state");
            let mut again = stale;
            assert_eq!(fmi2FreeFMUstate(c, &mut again), 3, "freed twice");
            assert_eq!(fmi2Reset(c), 0);
            let mut kept: Fmi2FmuState = std::ptr::null_mut();
            assert_eq!(fmi2GetFMUstate(c, &mut kept), 0);
            fmi2FreeInstance(c);
            fmi2FreeInstance(c);
            let mut x = 0.0;
            assert_eq!(fmi2GetReal(c, &h_vr, 1, &mut x), 3);
            assert_eq!(fmi2DoStep(c, 0.0, 0.01, 1), 3);
            // An instance's states go with it.
            let (d, _dir_d, _) = pendulum_instance();
            assert_eq!(fmi2SetFMUstate(d, kept), 3);
            // A pointer never given out.
            let mut junk = [0u64; 8];
            let wild = junk.as_mut_ptr() as Fmi2Component;
            assert_eq!(fmi2DoStep(wild, 0.0, 0.01, 1), 3);
            fmi2FreeInstance(wild);
            assert_eq!(junk, [0; 8], "a wild pointer is not written");
            fmi2FreeInstance(d);
        }
        // FMI 3.0 frees through the same registry.
        let text = pendulum_text();
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("scenario.toml"), &text).unwrap();
        let resources = CString::new(dir.path().display().to_string()).unwrap();
        let token = CString::new(spec.guid.clone()).unwrap();
        unsafe {
            let c = phstring_fmu::ffi3::fmi3InstantiateCoSimulation(
                c"t3".as_ptr(),
                token.as_ptr(),
                resources.as_ptr(),
                false,
                false,
                false,
                false,
                std::ptr::null(),
                0,
                std::ptr::null_mut(),
                None,
                std::ptr::null(),
            );
            assert!(!c.is_null());
            phstring_fmu::ffi3::fmi3FreeInstance(c);
            phstring_fmu::ffi3::fmi3FreeInstance(c);
            assert_eq!(phstring_fmu::ffi3::fmi3Reset(c), 3);
        }
    }

    /// Sixteen threads restore one saved state and step from it, on one instance, as fast
    /// as they can: every call is whole (the instance is locked per call), so `Ĥ` is
    /// always either the saved one or that after the step, bit for bit, and the balance is
    /// that of a single thread's step.
    #[test]
    fn calls_from_many_threads_on_one_instance_run_one_at_a_time() {
        let (c, _dir, spec) = pendulum_instance();
        let (h_vr, b_vr, fx_vr) = (
            vr_of(&spec, "H"),
            vr_of(&spec, "balance_error"),
            vr_of(&spec, "load0.F.x"),
        );
        let (s0, h0, h1, b1) = unsafe {
            assert_eq!(fmi2SetReal(c, &fx_vr, 1, &0.3), 0);
            let mut s0: Fmi2FmuState = std::ptr::null_mut();
            assert_eq!(fmi2GetFMUstate(c, &mut s0), 0);
            let (mut h0, mut h1, mut b1) = (0.0, 0.0, 0.0);
            assert_eq!(fmi2GetReal(c, &h_vr, 1, &mut h0), 0);
            assert_eq!(fmi2DoStep(c, 0.0, 0.05, 0), 0);
            assert_eq!(fmi2GetReal(c, &h_vr, 1, &mut h1), 0);
            assert_eq!(fmi2GetReal(c, &b_vr, 1, &mut b1), 0);
            (s0 as usize, h0, h1, b1)
        };
        assert_ne!(h0, h1);
        let handle = c as usize;
        let steps: usize = std::thread::scope(|scope| {
            let workers: Vec<_> = (0..16)
                .map(|_| {
                    scope.spawn(move || {
                        let c = handle as Fmi2Component;
                        let mut ok = 0;
                        for _ in 0..20 {
                            assert_eq!(fmi2SetFMUstate(c, s0 as Fmi2FmuState), 0);
                            // Another thread may have stepped since: then t is wrong (Error).
                            let s = fmi2DoStep(c, 0.0, 0.05, 0);
                            assert!(s == 0 || s == 3, "status {s}");
                            ok += usize::from(s == 0);
                            let mut h = 0.0;
                            // SAFETY: one valid element each.
                            assert_eq!(unsafe { fmi2GetReal(c, &h_vr, 1, &mut h) }, 0);
                            assert!(
                                h.to_bits() == h0.to_bits() || h.to_bits() == h1.to_bits(),
                                "H = {h}: neither {h0} nor {h1}"
                            );
                        }
                        ok
                    })
                })
                .collect();
            workers.into_iter().map(|w| w.join().unwrap()).sum()
        });
        assert!(steps > 0);
        unsafe {
            assert_eq!(fmi2SetFMUstate(c, s0 as Fmi2FmuState), 0);
            assert_eq!(fmi2DoStep(c, 0.0, 0.05, 0), 0);
            let (mut h, mut b) = (0.0, 0.0);
            assert_eq!(fmi2GetReal(c, &h_vr, 1, &mut h), 0);
            assert_eq!(fmi2GetReal(c, &b_vr, 1, &mut b), 0);
            assert_eq!((h.to_bits(), b.to_bits()), (h1.to_bits(), b1.to_bits()));
            fmi2FreeInstance(c);
        }
    }

    /// The C functions refuse an edited serialized state (its checksum).
    #[test]
    fn an_edited_state_is_refused_by_deserialize() {
        let (c, _dir, _) = pendulum_instance();
        unsafe {
            assert_eq!(fmi2DoStep(c, 0.0, 0.02, 1), 0);
            let mut state: Fmi2FmuState = std::ptr::null_mut();
            assert_eq!(fmi2GetFMUstate(c, &mut state), 0);
            let mut size = 0usize;
            assert_eq!(fmi2SerializedFMUstateSize(c, state, &mut size), 0);
            let mut bytes = vec![0u8; size];
            assert_eq!(
                fmi2SerializeFMUstate(c, state, bytes.as_mut_ptr() as *mut std::ffi::c_char, size),
                0
            );
            let mut copy: Fmi2FmuState = std::ptr::null_mut();
            let text = String::from_utf8(bytes.clone()).unwrap();
            let at = text.find("\"h0\":").unwrap() + 6;
            let mut edited = bytes.clone();
            edited[at] = if edited[at] == b'1' { b'2' } else { b'1' };
            assert_eq!(
                fmi2DeSerializeFMUstate(c, edited.as_ptr() as *const _, size, &mut copy),
                3
            );
            assert!(copy.is_null());
            assert_eq!(
                fmi2DeSerializeFMUstate(c, bytes.as_ptr() as *const _, size, &mut copy),
                0
            );
            assert_eq!(fmi2SetFMUstate(c, copy), 0);
            assert_eq!(fmi2DoStep(c, 0.02, 0.01, 1), 0);
            fmi2FreeInstance(c);
        }
    }
}

mod bodies {
    //! Rigid bodies in the FMU: their wrench ports as inputs, their states and port samples
    //! as outputs, against the library's run of the same scenario.

    use super::*;
    use phstring_fmu::model::{BodyValue, Quantity};

    /// examples/fmu/hook_block.toml: a 2 t hook block on two slings, its wrench an input.
    fn hook_block_text() -> String {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/fmu/hook_block.toml");
        std::fs::read_to_string(path).expect("examples/fmu/hook_block.toml")
    }

    /// examples/hook_block_3d.toml with the hook's wrench an input starting at `wrench`
    /// (force and torque expressions, 3 each).
    fn hook_block_3d_text(force: [&str; 3], torque: [&str; 3]) -> String {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/hook_block_3d.toml");
        let text = std::fs::read_to_string(path).expect("examples/hook_block_3d.toml");
        let q = |e: [&str; 3]| format!("[\"{}\", \"{}\", \"{}\"]", e[0], e[1], e[2]);
        let wrench = format!(
            "wrench = {{ force = {}, torque = {}, external = true }}\n",
            q(force),
            q(torque)
        );
        let anchor = "points = { top = [0.0, 0.0, 0.4], left = [-0.3, 0.0, -0.4], right = [0.3, 0.0, -0.4] }\n";
        assert!(text.contains(anchor));
        text.replacen(anchor, &format!("{anchor}{wrench}"), 1)
    }

    /// The hook block with its wrench's expressions `force` (2) and `torque` (1) [N, N·m];
    /// an FMU input if `external`.
    fn hook_block_with(force: [&str; 2], torque: &str, external: bool) -> String {
        let old = "wrench = { force = [\"0\", \"0\"], torque = [\"0\"], external = true }";
        let text = hook_block_text();
        assert!(text.contains(old));
        let new = format!(
            "wrench = {{ force = [\"{}\", \"{}\"], torque = [\"{torque}\"], external = {external} }}",
            force[0], force[1]
        );
        text.replace(old, &new)
    }

    /// The library's simulation of `text` (2D), started as `phstring run` starts it (at the
    /// equilibrium of `initial.equilibrium`).
    fn library_run<const D: usize>(text: &str) -> Simulation<D, Material> {
        let file = parse(text, Path::new("scenario.toml"), &[]).unwrap();
        let v = file.validate::<D>().unwrap();
        let setup = v.map_problem(phstring_io::scenario::Built::new).unwrap();
        setup.start(true, None).unwrap().0.problem
    }

    fn names(spec: &ModelSpec) -> Vec<(&str, Causality, &'static str)> {
        let body = |v: &&phstring_fmu::model::Variable| v.name.starts_with("body");
        let vars = spec.variables.iter().filter(body);
        vars.map(|v| (v.name.as_str(), v.causality, v.unit))
            .collect()
    }

    /// The variables of a 2D body: the wrench's force and torque inputs (starting at the
    /// expressions at t = 0), pose, velocities and the port's mid-step velocities; the units
    /// and their definitions in both model descriptions.
    #[test]
    fn variables_of_a_2d_hook_block() {
        use Causality::*;
        let spec = spec_of(&hook_block_with(["1.5e3 + t", "-200"], "30", true));
        assert_eq!(
            names(&spec),
            [
                ("body0.F.x", Input, "N"),
                ("body0.F.y", Input, "N"),
                ("body0.M.z", Input, "N.m"),
                ("body0.r.x", Output, "m"),
                ("body0.r.y", Output, "m"),
                ("body0.theta", Output, "rad"),
                ("body0.v.x", Output, "m/s"),
                ("body0.v.y", Output, "m/s"),
                ("body0.w.z", Output, "rad/s"),
                ("body0.vmid.x", Output, "m/s"),
                ("body0.vmid.y", Output, "m/s"),
                ("body0.wmid.z", Output, "rad/s"),
            ]
        );
        let start = |name: &str| {
            spec.variables
                .iter()
                .find(|v| v.name == name)
                .unwrap()
                .start
        };
        assert_eq!(start("body0.F.x"), Some(1.5e3));
        assert_eq!(start("body0.F.y"), Some(-200.0));
        assert_eq!(start("body0.M.z"), Some(30.0));
        let torque = spec
            .variables
            .iter()
            .find(|v| v.name == "body0.M.z")
            .unwrap();
        assert_eq!(
            torque.quantity,
            Quantity::BodyTorque {
                body: 0,
                component: 2
            }
        );
        assert!(
            torque.description.contains("\"hook\""),
            "{}",
            torque.description
        );
        for xml in [
            spec.model_description("hook"),
            spec.model_description_fmi3("hook"),
        ] {
            for unit in ["N.m", "rad", "rad/s"] {
                assert!(xml.contains(&format!("<Unit name=\"{unit}\">")), "{unit}");
            }
            assert!(xml.contains("with the rigid body hook (dimension 2)"));
        }
        // Without `external` the wrench is no input, but its port's outputs are there.
        let spec = spec_of(&hook_block_with(["0", "0"], "0", false));
        assert!(names(&spec).iter().all(|(_, c, _)| *c == Output));
        assert!(names(&spec).iter().any(|(n, ..)| *n == "body0.wmid.z"));
    }

    /// The variables of two 3D bodies: the hook's wrench inputs (3 + 3), the quaternion; the
    /// beam (no port) has its state only.
    #[test]
    fn variables_of_a_3d_hook_block_and_beam() {
        use Causality::*;
        let spec = spec_of(&hook_block_3d_text(["0", "0", "0"], ["0", "0", "0"]));
        let all = names(&spec);
        let inputs: Vec<&str> = all.iter().filter(|v| v.1 == Input).map(|v| v.0).collect();
        assert_eq!(
            inputs,
            [
                "body0.F.x",
                "body0.F.y",
                "body0.F.z",
                "body0.M.x",
                "body0.M.y",
                "body0.M.z"
            ]
        );
        let beam: Vec<&str> = all
            .iter()
            .map(|v| v.0)
            .filter(|n| n.starts_with("body1."))
            .collect();
        assert_eq!(
            beam,
            [
                "body1.r.x",
                "body1.r.y",
                "body1.r.z",
                "body1.q.w",
                "body1.q.x",
                "body1.q.y",
                "body1.q.z",
                "body1.v.x",
                "body1.v.y",
                "body1.v.z",
                "body1.w.x",
                "body1.w.y",
                "body1.w.z"
            ]
        );
        assert!(all.contains(&("body0.wmid.y", Output, "rad/s")));
        assert!(all.contains(&("body0.q.w", Output, "1")));
        // The beam starts turned 4° about y: q = (cos 2°, 0, sin 2°, 0).
        let (mut inst, _) = instance(&hook_block_3d_text(["0", "0", "0"], ["0", "0", "0"]));
        initialize(&mut inst);
        let half = 2f64.to_radians();
        assert!((get(&mut inst, "body1.q.w") - half.cos()).abs() <= 1e-15);
        assert!((get(&mut inst, "body1.q.y") - half.sin()).abs() <= 1e-15);
        assert_eq!(get(&mut inst, "body1.w.z"), 0.05);
    }

    /// A constant wrench held by the master over communication steps of five internal steps
    /// is `phstring run` of the same wrench as expressions, switched on after `t = 0` (both
    /// started at the equilibrium without it, the FMU's inputs starting at the expressions'
    /// zero): every body output and the energies agree to 1e-12 relative, and the balance
    /// holds to round-off of the block's potential energy (~1e5 J).
    #[test]
    fn a_held_wrench_is_the_run_of_the_same_wrench_as_expressions() {
        let (f, tau) = (["3000*(t > 0)", "-1000*(t > 0)"], "200*(t > 0)");
        let (mut inst, _) = instance(&hook_block_with(f, tau, true));
        initialize(&mut inst);
        let mut sim = library_run::<2>(&hook_block_with(f, tau, false));
        let close = |a: f64, b: f64, scale: f64| (a - b).abs() <= 1e-12 * scale.max(b.abs());
        let start = ["body0.r.x", "body0.r.y", "body0.theta"].map(|n| get(&mut inst, n));
        let h_comm = 0.05;
        for n in 0..40 {
            let t = n as f64 * h_comm;
            assert_eq!(set(&mut inst, "body0.F.x", 3000.0), Status::Ok);
            assert_eq!(set(&mut inst, "body0.F.y", -1000.0), Status::Ok);
            assert_eq!(set(&mut inst, "body0.M.z", 200.0), Status::Ok);
            assert_eq!(inst.do_step(t, h_comm), Status::Ok, "step {n}");
            while sim.time() < t + h_comm - 1e-12 {
                sim.step_until(t + h_comm).unwrap();
            }
            let (st, port) = (&sim.state().bodies[0], &sim.body_ports()[0]);
            let pairs = [
                ("body0.r.x", st.position.x, 1.0),
                ("body0.r.y", st.position.y, 1.0),
                ("body0.v.x", st.velocity.x, 1e-3),
                ("body0.w.z", st.omega_space().z, 1e-3),
                ("body0.vmid.x", port.velocity.x, 1e-3),
                ("body0.wmid.z", port.omega.z, 1e-3),
                ("H", sim.energies().hamiltonian(), 1e5),
                ("T", sim.energies().kinetic, 1e5),
                ("supplied", sim.supplied_energy(), 1e5),
            ];
            for (name, run, scale) in pairs {
                let fmu = get(&mut inst, name);
                assert!(close(fmu, run, scale), "step {n}: {name} {fmu} vs {run}");
            }
            assert!(
                get(&mut inst, "balance_error").abs() <= 1e-12 * 1e5,
                "step {n}"
            );
        }
        // The angle is the quaternion's.
        let q = sim.state().bodies[0].orientation;
        assert!(close(
            get(&mut inst, "body0.theta"),
            q.angle() * q.axis().map_or(1.0, |a| a.z),
            1.0
        ));
        // The block moved: the slings' V holds it sideways, so 3 kN move it by millimetres.
        let x = get(&mut inst, "body0.r.x");
        assert!(1e-3 < x - start[0] && x - start[0] < 0.1, "{x}");
        // Then communication steps of one internal step each: the wrench's work over them is
        // (20.2), F·Δx + τ Σ w_n with the steps' Cayley vectors w_n = h·wmid.z (in 2D R_n w is
        // w), to round-off.
        let before = ["body0.r.x", "body0.r.y", "supplied"].map(|n| get(&mut inst, n));
        let mut turns = 0.0;
        for n in 0..50 {
            let t = 2.0 + n as f64 * 0.01;
            set(&mut inst, "body0.F.x", 3000.0);
            set(&mut inst, "body0.F.y", -1000.0);
            set(&mut inst, "body0.M.z", 200.0);
            assert_eq!(inst.do_step(t, 0.01), Status::Ok);
            turns += 0.01 * get(&mut inst, "body0.wmid.z");
        }
        let after = ["body0.r.x", "body0.r.y", "supplied"].map(|n| get(&mut inst, n));
        let work =
            3000.0 * (after[0] - before[0]) - 1000.0 * (after[1] - before[1]) + 200.0 * turns;
        let supplied = after[2] - before[2];
        assert!(work.abs() > 1e-3, "{work}");
        // Round-off of ~50 products of 1e3 N and 1e-4 m, and of the sums near 16 J.
        assert!((supplied - work).abs() <= 1e-11, "{supplied} vs {work}");
    }

    /// With `initial.equilibrium`, the FMU starts at rest at the equilibrium under the wrench
    /// inputs set before initialization ends (held on the system for the statics): the
    /// library's start under the same wrench as expressions, to 1e-12 m, and it stays there
    /// under those inputs (the statics' residual, 1e-6 N on 2e4 N, leaves µm/s at most).
    #[test]
    fn an_equilibrium_start_is_under_the_wrench_inputs() {
        let (mut inst, _) = instance(&hook_block_text());
        assert_eq!(set(&mut inst, "body0.F.x", 4000.0), Status::Ok);
        assert_eq!(set(&mut inst, "body0.F.y", -1000.0), Status::Ok);
        initialize(&mut inst);
        let sim = library_run::<2>(&hook_block_with(["4000", "-1000"], "0", false));
        let at = sim.state().bodies[0].position;
        let x = get(&mut inst, "body0.r.x");
        assert!((x - at.x).abs() <= 1e-12, "{x} vs {}", at.x);
        assert!((get(&mut inst, "body0.r.y") - at.y).abs() <= 1e-12);
        // Under 4 kN the block stands 1e-3 m and more off its rest without a force.
        let free = library_run::<2>(&hook_block_text()).state().bodies[0].position;
        assert!((x - free.x).abs() > 1e-3, "{x} vs {}", free.x);
        for n in 0..20 {
            assert_eq!(inst.do_step(n as f64 * 0.01, 0.01), Status::Ok);
        }
        assert!(get(&mut inst, "body0.v.x").abs() < 1e-5);
        assert!(get(&mut inst, "T") < 1e-6, "{}", get(&mut inst, "T"));
    }

    /// A 3D hook block and beam with a constant force and torque on the hook from the
    /// master: the run of the same wrench to 1e-12, the balance to round-off, unit
    /// quaternions.
    #[test]
    fn a_3d_wrench_input_is_the_run() {
        let (force, torque) = (["500", "-300", "2000"], ["0", "0", "150"]);
        let text = hook_block_3d_text(force, torque);
        let (mut inst, _) = instance(&text);
        initialize(&mut inst);
        let mut sim = library_run::<3>(&text.replace("external = true", "external = false"));
        for n in 0..10 {
            let t = n as f64 * 0.02;
            for (name, x) in [
                ("F.x", 500.0),
                ("F.y", -300.0),
                ("F.z", 2000.0),
                ("M.z", 150.0),
            ] {
                assert_eq!(set(&mut inst, &format!("body0.{name}"), x), Status::Ok);
            }
            assert_eq!(inst.do_step(t, 0.02), Status::Ok);
            while sim.time() < t + 0.02 - 1e-12 {
                sim.step_until(t + 0.02).unwrap();
            }
        }
        let b = &sim.state().bodies;
        let q = b[0].orientation.quaternion();
        let pairs = [
            ("body0.r.z", b[0].position.z, 10.0),
            ("body0.q.z", q.k, 1.0),
            ("body1.w.z", b[1].omega_space().z, 0.05),
            ("body0.wmid.z", sim.body_ports()[0].omega.z, 0.05),
            ("H", sim.energies().hamiltonian(), 1e6),
        ];
        for (name, run, scale) in pairs {
            let fmu = get(&mut inst, name);
            assert!((fmu - run).abs() <= 1e-12 * scale, "{name} {fmu} vs {run}");
        }
        let norm: f64 = ["w", "x", "y", "z"]
            .iter()
            .map(|c| get(&mut inst, &format!("body0.q.{c}")).powi(2))
            .sum();
        assert!((norm - 1.0).abs() <= 1e-14, "{norm}");
        // H ~ 1.2e6 J (5.6 t at ~21 m): the balance to round-off.
        assert!(get(&mut inst, "balance_error").abs() <= 1e-12 * 1.2e6);
        assert!(get(&mut inst, "supplied").abs() > 0.0);
    }

    /// The hook block hanging from a crab whose motion is prescribed: the crab's outputs are
    /// the reaction force and torque of its motion, the library's to 1e-12, the balance to
    /// round-off; and the reaction carries the suspension's weight on average.
    #[test]
    fn a_prescribed_body_reports_its_reaction() {
        let text = hook_block_text()
            .replace("[[node]]\nname = \"left\"\nposition = [-3.0, 0.0]\n\n", "")
            .replace("[[node]]\nname = \"right\"\nposition = [3.0, 0.0]\n\n", "")
            .replace(
                "[materials.sling]",
                "[bodies.crab]\nmass = 500.0\ninertia = [0.0, 0.0, 50.0]\nposition = [0.0, 0.0]\npoints = { left = [-3.0, 0.0], right = [3.0, 0.0] }\nmotion = { position = [\"0.5*(1 - cos(t))\", \"0\"] }\n\n[materials.sling]",
            )
            .replace("path = [\"left\"", "path = [\"crab.left\"")
            .replace("path = [\"right\"", "path = [\"crab.right\"")
            .replace("[[boundary]]\nnode = \"left\"\nfixed = true                           # its reaction (support0.R) is an output\n\n", "")
            .replace("[[boundary]]\nnode = \"right\"\nfixed = true                           # support1.R\n\n", "")
            // The crab starts moving: the block from its given pose (near its rest).
            .replace("equilibrium = true", "equilibrium = false");
        let spec = spec_of(&text);
        let crab: Vec<&str> = names(&spec)
            .into_iter()
            .map(|v| v.0)
            .filter(|n| n.starts_with("body1."))
            .collect();
        assert_eq!(
            crab,
            [
                "body1.r.x",
                "body1.r.y",
                "body1.theta",
                "body1.v.x",
                "body1.v.y",
                "body1.w.z",
                "body1.RF.x",
                "body1.RF.y",
                "body1.RM.z"
            ]
        );
        let (mut inst, log) = instance(&text);
        assert_eq!(inst.setup_experiment(0.0, None), Status::Ok);
        assert_eq!(inst.enter_initialization(), Status::Ok);
        let init = inst.exit_initialization();
        assert_eq!(init, Status::Ok, "{}", last_message(&log));
        let mut sim = library_run::<2>(&text.replace("external = true", "external = false"));
        let mut mean_ry = 0.0;
        let steps = 100;
        for n in 0..steps {
            let t = n as f64 * 0.01;
            assert_eq!(inst.do_step(t, 0.01), Status::Ok);
            sim.step().unwrap();
            let port = &sim.body_ports()[1];
            for (name, run) in [
                ("body1.RF.x", port.force.x),
                ("body1.RF.y", port.force.y),
                ("body1.RM.z", port.torque.z),
            ] {
                let fmu = get(&mut inst, name);
                assert!((fmu - run).abs() <= 1e-12 * 3e4, "{name} {fmu} vs {run}");
            }
            mean_ry += get(&mut inst, "body1.RF.y") / steps as f64;
        }
        // The crab moves 0.5 (1 − cos t) m: at t = 1 s it is at 0.23 m.
        assert!((get(&mut inst, "body1.r.x") - 0.5 * (1.0 - 1f64.cos())).abs() <= 1e-12);
        // Over 1 s the motion holds the crab, the slings and the block (500 + 2·5.86·2 +
        // 2000 kg, 24.75 kN) up to their mean vertical acceleration: the block's bounce from
        // its start near rest averages out, the crab moves sideways only.
        let weight = (500.0 + 2.0 * 5.86 * 2.0 + 2000.0) * 9.81;
        assert!(
            (mean_ry - weight).abs() <= 1e-3 * weight,
            "{mean_ry} vs {weight}"
        );
        let h = get(&mut inst, "H").abs();
        assert!(get(&mut inst, "balance_error").abs() <= 1e-12 * h.max(1e5));
    }

    /// A saved state carries the bodies (the checkpoint's poses and velocities, the ports'
    /// samples): restored, in the same and in another instance through its serialized
    /// form, it continues bit for bit, and serves the body port outputs of the saved point.
    #[test]
    fn saved_states_with_bodies_continue_bit_for_bit() {
        let text = hook_block_text();
        let (mut a, _) = instance(&text);
        initialize(&mut a);
        let outputs = [
            "H",
            "body0.r.x",
            "body0.theta",
            "body0.w.z",
            "body0.vmid.y",
            "balance_error",
        ];
        let run = |inst: &mut Instance, from: usize, to: usize| -> Vec<u64> {
            let mut bits = Vec::new();
            for n in from..to {
                let t = n as f64 * 0.02;
                set(inst, "body0.F.x", 2000.0 * (t * 1.3).sin());
                set(inst, "body0.M.z", 100.0 * (t * 0.7).cos());
                assert_eq!(inst.do_step(t, 0.02), Status::Ok);
                bits.extend(outputs.iter().map(|o| get(inst, o).to_bits()));
            }
            bits
        };
        run(&mut a, 0, 20);
        let vmid = get(&mut a, "body0.vmid.x");
        assert!(vmid.abs() > 1e-3, "the block moves: {vmid}");
        let saved = a.save().unwrap();
        let first = run(&mut a, 20, 50);
        assert_eq!(a.restore(&saved), Status::Ok);
        assert_eq!(get(&mut a, "body0.vmid.x").to_bits(), vmid.to_bits());
        assert_eq!(run(&mut a, 20, 50), first);
        let bytes = saved.to_bytes().unwrap();
        let back = phstring_fmu::instance::Saved::from_bytes(&bytes).unwrap();
        let (mut b, _) = instance(&text);
        initialize(&mut b);
        assert_eq!(b.restore(&back), Status::Ok);
        assert_eq!(get(&mut b, "body0.vmid.x").to_bits(), vmid.to_bits());
        assert_eq!(run(&mut b, 20, 50), first);
        let q = |v: &phstring_fmu::model::Variable| {
            matches!(
                v.quantity,
                Quantity::Body {
                    what: BodyValue::Angle,
                    ..
                }
            )
        };
        assert!(b.spec().variables.iter().any(q));
    }

    /// A wrench expression that is not finite at t = 0 cannot be an input's start value: the
    /// error names the body's key.
    #[test]
    fn a_start_wrench_that_is_not_finite_is_refused_by_its_key() {
        let text = hook_block_with(["1/t", "0"], "0", true);
        let file = parse(&text, Path::new("scenario.toml"), &[]).unwrap();
        let err = ModelSpec::new(&file).unwrap_err().to_string();
        assert!(
            err.contains("bodies.hook.wrench") && err.contains("body0.F.x"),
            "{err}"
        );
    }
}

mod winches {
    //! Winches in the FMU (docs/method.md §20, §23): the payout speed of a winch marked
    //! `external = true` as an input, every winch's payout, length, speed, tension, power and
    //! energy as outputs, against the library driven by `set_winch_speed`.

    use super::*;

    /// examples/crane_hoisting_2d.toml with the trolley at rest and the payout an input.
    fn crane_text() -> String {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/crane_hoisting_2d.toml");
        let text = std::fs::read_to_string(path).expect("examples/crane_hoisting_2d.toml");
        let payout = "payout = \"-15 * (3*min(t/30,1)^2 - 2*min(t/30,1)^3)\"";
        let drum = "drum_position = [\"6 * (3*min(t/8,1)^2 - 2*min(t/8,1)^3)\", \"0\"]";
        assert!(text.contains(payout) && text.contains(drum));
        text.replace(payout, "external = true").replace(drum, "")
    }

    /// The library's simulation of `text`, started as `phstring run` starts it.
    fn library_run(text: &str) -> Simulation<2, Material> {
        let file = parse(text, Path::new("scenario.toml"), &[]).unwrap();
        let v = file.validate::<2>().unwrap();
        let setup = v.map_problem(phstring_io::scenario::Built::new).unwrap();
        setup.start(true, None).unwrap().0.problem
    }

    /// The crane's winch variables: the speed input (start 0) and the six outputs, with
    /// their units, in both model descriptions (the unit `W` defined).
    #[test]
    fn variables_of_an_external_winch() {
        use Causality::*;
        let spec = spec_of(&crane_text());
        let winch: Vec<_> = spec
            .variables
            .iter()
            .filter(|v| v.name.starts_with("winch."))
            .map(|v| (v.name.as_str(), v.causality, v.unit, v.start))
            .collect();
        assert_eq!(
            winch,
            [
                ("winch.hoist.speed", Input, "m/s", Some(0.0)),
                ("winch.hoist.payout", Output, "m", None),
                ("winch.hoist.length", Output, "m", None),
                ("winch.hoist.vmid", Output, "m/s", None),
                ("winch.hoist.tension", Output, "N", None),
                ("winch.hoist.power", Output, "W", None),
                ("winch.hoist.energy", Output, "J", None),
            ]
        );
        for xml in [
            spec.model_description("crane"),
            spec.model_description_fmi3("crane"),
        ] {
            assert!(xml.contains("name=\"winch.hoist.speed\""));
            assert!(xml.contains("name=\"winch.hoist.power\""));
            assert!(xml.contains("<Unit name=\"W\">"));
        }
        // A winch whose payout is an expression has the outputs and no input.
        let plain = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/crane_hoisting_2d.toml"),
        )
        .unwrap();
        let spec = spec_of(&plain);
        let names: Vec<_> = spec
            .variables
            .iter()
            .filter(|v| v.name.starts_with("winch."))
            .map(|v| (v.name.as_str(), v.causality))
            .collect();
        assert_eq!(names.len(), 6);
        assert!(names.iter().all(|(_, c)| *c == Output));
    }

    /// Speeds set by the master over communication steps of five internal steps are the
    /// library's run with the same speeds held by `set_winch_speed`, bit for bit (the FMU
    /// holds them with that call); the payout is the sum of speed × H to round-off, and the
    /// winch's energy is `supplied` and `Ĥ(t) − Ĥ(0)` (its only port). A state saved mid-run
    /// and restored reports the outputs of its last step (speed and power are not in the
    /// simulation's checkpoint) and continues bit for bit.
    #[test]
    fn held_speeds_are_the_library_run_bit_for_bit_and_states_continue() {
        let text = crane_text();
        let (mut inst, _) = instance(&text);
        initialize(&mut inst);
        let mut sim = library_run(&text);
        let h0 = get(&mut inst, "H");
        assert_eq!(h0.to_bits(), sim.energies().hamiltonian().to_bits());
        let h_comm = 0.05;
        // Haul in: a ramp to 0.2 m/s over 1 s, then constant.
        let speed = |n: usize| -0.2 * ((n as f64 + 0.5) * h_comm).min(1.0);
        let names = [
            "winch.hoist.payout",
            "winch.hoist.length",
            "winch.hoist.vmid",
        ];
        let more = [
            "winch.hoist.tension",
            "winch.hoist.power",
            "winch.hoist.energy",
            "H",
        ];
        let outputs = |inst: &mut Instance| {
            names
                .iter()
                .chain(&more)
                .map(|n| get(inst, n))
                .collect::<Vec<f64>>()
        };
        let mut paid = 0.0;
        let mut saved = None;
        let mut after_save = Vec::new();
        for n in 0..60 {
            let t = n as f64 * h_comm;
            assert_eq!(set(&mut inst, "winch.hoist.speed", speed(n)), Status::Ok);
            assert_eq!(inst.do_step(t, h_comm), Status::Ok, "step {n}");
            sim.set_winch_speed(0, speed(n)).unwrap();
            while sim.time() < t + h_comm - 1e-12 {
                sim.step_until(t + h_comm).unwrap();
            }
            paid += speed(n) * h_comm;
            let w = sim.winch_samples()[0];
            let lib = [
                w.payout,
                w.length,
                w.speed,
                w.tension,
                w.power,
                w.energy,
                sim.energies().hamiltonian(),
            ];
            let fmu = outputs(&mut inst);
            for (k, (a, b)) in fmu.iter().zip(lib).enumerate() {
                assert_eq!(a.to_bits(), b.to_bits(), "step {n}, output {k}: {a} vs {b}");
            }
            // 60 steps of rounding on a payout of up to 0.5 m.
            assert!((w.payout - paid).abs() <= 1e-13, "{} vs {paid}", w.payout);
            assert!(
                (w.speed - speed(n)).abs() <= 1e-12,
                "{} vs {}",
                w.speed,
                speed(n)
            );
            let supplied = get(&mut inst, "supplied");
            assert!((w.energy - supplied).abs() <= 1e-9 * supplied.abs().max(1.0));
            assert!((fmu[6] - h0 - w.energy).abs() <= 1e-9 * w.energy.abs().max(1.0));
            assert!(get(&mut inst, "balance_error").abs() <= 1e-12 * h0.abs());
            if n == 30 {
                saved = Some((inst.save().unwrap(), fmu));
            } else if n > 30 {
                after_save.push(fmu);
            }
        }
        assert!(paid < -0.5 && get(&mut inst, "winch.hoist.energy") > 1e4);
        let (state, at_save) = saved.unwrap();
        let (mut other, _) = instance(&text);
        initialize(&mut other);
        assert_eq!(other.restore(&state), Status::Ok);
        let restored = outputs(&mut other);
        assert_eq!(
            restored.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            at_save.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        for (k, row) in after_save.iter().enumerate() {
            let n = 31 + k;
            let t = n as f64 * h_comm;
            assert_eq!(set(&mut other, "winch.hoist.speed", speed(n)), Status::Ok);
            assert_eq!(other.do_step(t, h_comm), Status::Ok);
            let again = outputs(&mut other);
            assert_eq!(
                again.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                row.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                "step {n}"
            );
        }
    }
}
