//! What the FMU layer costs per step: the library stepping to the same communication points
//! (`Simulation::step_until`) against `Instance::do_step` driven as a master drives it (set
//! the inputs, step, read all outputs), with communication steps of one and of ten
//! internal steps. Both runs end with the same `Ĥ`, bit for bit (asserted).
//! `cargo bench -p phstring-fmu --bench overhead`: best-of-5 wall times, release mode.

use std::path::Path;
use std::time::Instant;

use phstring::{Material, Simulation};
use phstring_fmu::instance::{Instance, Status};
use phstring_fmu::model::{Causality, ModelSpec};
use phstring_io::scenario::parse;

fn best_of<F: FnMut() -> f64>(mut f: F) -> f64 {
    (0..5).map(|_| f()).fold(f64::INFINITY, f64::min)
}

fn instance(text: &str) -> Instance {
    let file = parse(text, Path::new("scenario.toml"), &[]).unwrap();
    let spec = ModelSpec::new(&file).unwrap();
    let mut i = Instance::new(
        "bench",
        &spec.guid,
        text.to_string(),
        "scenario.toml".into(),
        Box::new(|_, _, _| {}),
        false,
    )
    .unwrap();
    assert_eq!(i.setup_experiment(0.0, None), Status::Ok);
    assert_eq!(i.enter_initialization(), Status::Ok);
    assert_eq!(i.exit_initialization(), Status::Ok);
    i
}

/// Wall time [s] of the library stepping to `comms` communication points `per` steps of
/// `h` apart, and its final `Ĥ` [J].
fn library(text: &str, h: f64, comms: usize, per: usize) -> (f64, f64) {
    // The force the master sets below (0.1 N per component), as a scenario expression.
    let file = parse(
        text,
        Path::new("scenario.toml"),
        &["boundary.1.force=[\"0.1\", \"0.1\"]".to_string()],
    )
    .unwrap();
    let mut energy = 0.0;
    let wall = best_of(|| {
        let v = file.validate::<2>().unwrap();
        let mut sim: Simulation<2, Material> = Simulation::new(v.problem, v.settings.step).unwrap();
        let start = Instant::now();
        for n in 0..comms {
            let target = (n * per) as f64 * h + per as f64 * h;
            while sim.time() < target - 1e-9 * h {
                sim.step_until(target).unwrap();
            }
        }
        let wall = start.elapsed().as_secs_f64();
        energy = sim.energies().hamiltonian();
        wall
    });
    (wall, energy)
}

/// Wall time [s] of the FMU instance over the same communication points, and its final `Ĥ`.
fn fmu(text: &str, h: f64, comms: usize, per: usize) -> (f64, f64) {
    let spec = ModelSpec::new(&parse(text, Path::new("scenario.toml"), &[]).unwrap()).unwrap();
    let of = |c: Causality| -> Vec<u32> {
        (0..spec.variables.len() as u32)
            .filter(|&k| spec.variables[k as usize].causality == c)
            .collect()
    };
    let (inputs, outputs) = (of(Causality::Input), of(Causality::Output));
    let h_vr = spec.variables.iter().position(|v| v.name == "H").unwrap() as u32;
    let mut energy = 0.0;
    let wall = best_of(|| {
        let mut inst = instance(text);
        let mut out = vec![0.0; outputs.len()];
        let values = vec![0.1; inputs.len()];
        let start = Instant::now();
        for n in 0..comms {
            assert_eq!(inst.set_real(&inputs, &values), Status::Ok);
            let t = (n * per) as f64 * h;
            assert_eq!(inst.do_step(t, per as f64 * h), Status::Ok);
            assert_eq!(inst.get_real(&outputs, &mut out), Status::Ok);
        }
        let wall = start.elapsed().as_secs_f64();
        let mut e = [0.0];
        assert_eq!(inst.get_real(&[h_vr], &mut e), Status::Ok);
        energy = e[0];
        wall
    });
    (wall, energy)
}

fn case(label: &str, text: &str, steps: usize) {
    let h = *parse(text, Path::new("scenario.toml"), &[])
        .unwrap()
        .scenario
        .time
        .h
        .get_ref();
    for per in [1, 10] {
        let comms = steps / per;
        let (lib, e_lib) = library(text, h, comms, per);
        let (fmu, e_fmu) = fmu(text, h, comms, per);
        assert_eq!(e_lib.to_bits(), e_fmu.to_bits(), "{label}: the runs differ");
        let us = |s: f64| 1e6 * s / comms as f64;
        println!(
            "{label:<28} H = {per:>2} h, {comms:>5} communication steps: library {:>10.2} µs, FMU {:>10.2} µs per communication step ({:+.2} µs, {:+.1} %)",
            us(lib),
            us(fmu),
            us(fmu) - us(lib),
            100.0 * (fmu / lib - 1.0)
        );
    }
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let read = |p: &str| std::fs::read_to_string(root.join(p)).unwrap();
    // Both scenarios have their external force port as boundary table 1.
    let pendulum = read("examples/fmu/pendulum.toml");
    case("pendulum N = 30", &pendulum, 1000);
    case(
        "pendulum N = 3000",
        &pendulum.replace("elements = 30", "elements = 3000"),
        100,
    );
    case(
        "hoist rope N = 20 + 200 kg",
        &read("examples/fmu/hoist.toml"),
        2000,
    );
}
