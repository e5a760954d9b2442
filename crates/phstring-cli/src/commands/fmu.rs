//! `phstring fmu`: the FMI Co-Simulation FMU of a scenario.

use std::path::PathBuf;

use anyhow::{Context as _, Result, anyhow, bail};
use phstring_fmu::{model::ModelSpec, package};

use crate::budget::check_budget;

/// Environment variable naming the FMU's shared library (instead of looking next to the
/// `phstring` executable).
const FMU_LIBRARY_ENV: &str = "PHSTRING_FMU_LIBRARY";

// The arguments of `phstring fmu`; their help text is the doc comment of the
// command's variant in `Command`.
#[derive(clap::Args)]
pub struct FmuArgs {
    /// Scenario file (TOML), or a MoorDyn input deck (told by its content).
    pub scenario: PathBuf,
    /// The FMU file to write; its name (without .fmu) is the model identifier.
    #[arg(short, long, value_name = "NAME.fmu")]
    pub out: PathBuf,
    /// Override a scenario key by its dotted path (the FMU holds the result).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// The FMU's shared library (default: the one built next to this executable, or
    /// $PHSTRING_FMU_LIBRARY).
    #[arg(long, value_name = "PATH")]
    pub library: Option<PathBuf>,
    /// FMI version: 2 (2.0, the version most tools import) or 3 (3.0).
    #[arg(long = "fmi-version", value_name = "2|3", default_value = "2", value_parser = ["2", "3"])]
    pub fmi_version: String,
    /// Replace an existing file NAME.fmu.
    #[arg(long)]
    pub force: bool,
    /// For a MoorDyn deck: drop a feature phstring does not model (EI, rods, bodies, …;
    /// docs/moordyn.md).
    #[arg(long = "ignore", value_name = "FEATURE")]
    pub ignore: Vec<String>,
}

/// `phstring fmu`: writes the FMI 2.0 (or 3.0) Co-Simulation FMU of the scenario of `args`;
/// an existing file `--out` is replaced only with `--force`.
pub fn fmu(args: FmuArgs) -> Result<()> {
    let version = if args.fmi_version == "3" {
        package::FmiVersion::V3
    } else {
        package::FmiVersion::V2
    };
    let FmuArgs {
        scenario,
        out,
        sets,
        library,
        force,
        ignore,
        ..
    } = args;
    let (path, out) = (scenario.as_path(), out.as_path());
    if out.extension().and_then(|e| e.to_str()) != Some("fmu") {
        bail!(
            "-o {}: an FMU's file name ends in .fmu (e.g. -o crane.fmu)",
            out.display()
        );
    }
    if out.is_dir() {
        bail!("-o {}: is a folder, not a file name", out.display());
    }
    // Anything at the name, a dangling symbolic link included.
    if !force && std::fs::symlink_metadata(out).is_ok() {
        bail!(
            "-o {}: the file exists; give --force to replace it",
            out.display()
        );
    }
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let identifier =
        package::model_identifier(&stem).map_err(|e| anyhow!("-o {}: {e}", out.display()))?;
    let file = phstring_io::moordyn::load_scenario(path, &sets, &ignore)?.file;
    check_budget(&file)?;
    let spec = ModelSpec::new(&file)?;
    let library = match library.or_else(|| std::env::var_os(FMU_LIBRARY_ENV).map(PathBuf::from)) {
        Some(l) => l,
        None => {
            let exe = std::env::current_exe().context("cannot locate the phstring executable")?;
            let candidates = package::library_candidates(&exe);
            match candidates.iter().find(|p| p.is_file()) {
                Some(p) => p.clone(),
                None => bail!(
                    "the FMU's shared library {} is not next to {} (looked in {}); build it with `cargo build --release -p phstring-fmu`, then give it with --library PATH or {FMU_LIBRARY_ENV}",
                    package::library_file_name(),
                    exe.display(),
                    candidates
                        .iter()
                        .map(|p| p.display().to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            }
        }
    };
    package::write_fmu(&file, &spec, &identifier, &library, out, version)?;
    let count = |c: phstring_fmu::model::Causality| {
        spec.variables.iter().filter(|v| v.causality == c).count()
    };
    use phstring_fmu::model::Causality as C;
    say!(
        "wrote {} (FMI {} Co-Simulation, model identifier {identifier}): {} inputs, {} outputs, {} parameters",
        out.display(),
        if version == package::FmiVersion::V3 {
            "3.0"
        } else {
            "2.0"
        },
        count(C::Input),
        count(C::Output),
        count(C::Parameter)
    );
    if count(C::Input) == 0 {
        say!(
            "  no inputs: mark a [[boundary]] table's force or position, or a body's wrench, with external = true to make it one"
        );
    }
    for v in &spec.variables {
        say!(
            "  {:<10} {:<22} [{}]",
            match v.causality {
                C::Parameter => "parameter",
                C::Input => "input",
                C::Output => "output",
            },
            v.name,
            v.unit
        );
    }
    Ok(())
}
