//! Building firmware with cargo: the bench firmware workspace (`bench/firmware`) and the
//! firmware examples of the twocan workspace (`examples/*`).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use crate::cmd::{self, Context, Error, Result};

/// The cross target of every firmware.
pub const TARGET: &str = "thumbv7em-none-eabihf";

/// Time allowed for one cargo build.
const BUILD_LIMIT: Duration = Duration::from_secs(900);

/// Where things are.
#[derive(Debug, Clone)]
pub struct Paths {
    /// The twocan workspace root.
    pub root: PathBuf,
    /// The target directory base: `$CARGO_TARGET_DIR` or `<root>/target`.
    pub target: PathBuf,
}

impl Paths {
    /// From this package's location (`<root>/bench`).
    pub fn discover() -> Result<Paths> {
        let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
        let root = manifest
            .parent()
            .ok_or_else(|| Error::new("bench/ has no parent directory"))?
            .to_path_buf();
        if !root.join("Cargo.toml").is_file() {
            return Err(Error::new(format!(
                "{} is not the twocan workspace (no Cargo.toml)",
                root.display()
            )));
        }
        let target = match std::env::var_os("CARGO_TARGET_DIR") {
            Some(t) if !t.is_empty() => {
                let t = PathBuf::from(t);
                if t.is_absolute() {
                    t
                } else {
                    root.join(t)
                }
            }
            _ => root.join("target"),
        };
        Ok(Paths { root, target })
    }

    /// The bench firmware workspace.
    pub fn firmware(&self) -> PathBuf {
        self.root.join("bench").join("firmware")
    }

    /// A directory of our own under the target directory.
    pub fn scratch(&self, name: &str) -> PathBuf {
        self.target.join(name)
    }
}

/// The cargo that runs us (`$CARGO`, set by `cargo run`), else `cargo` from `PATH`.
pub fn cargo() -> Command {
    let program = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut c = Command::new(program);
    // The child gets an explicit --target-dir; variables of the outer build must not leak.
    for var in [
        "CARGO_TARGET_DIR",
        "CARGO_BUILD_TARGET",
        "CARGO_BUILD_TARGET_DIR",
        "RUSTFLAGS",
        "CARGO_ENCODED_RUSTFLAGS",
    ] {
        c.env_remove(var);
    }
    c
}

/// Makes sure the cross target is installed; `rustup target add` only when `install`
/// (`--install`) is set, otherwise an error says how to get it.
pub fn ensure_target(install: bool) -> Result<()> {
    let Some(rustup) = cmd::which("rustup") else {
        // No rustup: the build itself will say whether the target's std is there.
        return Ok(());
    };
    let out = cmd::run_ok(
        Command::new(&rustup).args(["target", "list", "--installed"]),
        Duration::from_secs(60),
    )?;
    if out.stdout.lines().any(|l| l.trim() == TARGET) {
        return Ok(());
    }
    if !install {
        return Err(Error::new(format!(
            "the {TARGET} target (needed to cross-build the firmware) is not installed: run \
             `rustup target add {TARGET}`, or `can-bench --install` to let can-bench do it"
        )));
    }
    eprintln!("can-bench: installing the {TARGET} target (rustup target add {TARGET}, --install)");
    cmd::run_ok(
        Command::new(&rustup).args(["target", "add", TARGET]),
        Duration::from_secs(600),
    )
    .context(format!(
        "the {TARGET} target is needed to cross-build the firmware"
    ))?;
    Ok(())
}

/// Builds the bench firmware workspace with cargo profile `profile`; returns the
/// directory holding its ELFs. The packages of [`VARIANT_PACKAGES`] are built once per
/// variant of [`VARIANTS`] (cargo feature of the same name), those of
/// [`FEATURE_PACKAGES`] once more per one-feature variant of [`FEATURE_VARIANTS`]
/// (features `lean` and the choice's), and their ELFs copied to `<bin>-<variant>` in
/// that directory.
pub fn bench_firmware(paths: &Paths, profile: &str) -> Result<PathBuf> {
    let target_dir = paths.scratch("bench-firmware");
    let manifest = paths.firmware().join("Cargo.toml");
    let out = target_dir.join(TARGET).join(profile);
    // One cargo invocation per feature set: cargo unifies features over the packages of
    // one build, so the `async` feature of the async firmwares and each variant's
    // features must not meet the other firmwares.
    let mut selections: Vec<(Vec<String>, Option<Copies>)> = Vec::new();
    let mut rest = vec!["--workspace".to_string()];
    for p in ASYNC_PACKAGES
        .iter()
        .chain(VARIANT_PACKAGES.iter().map(|(p, _)| p))
    {
        rest.extend(["--exclude".to_string(), p.to_string()]);
    }
    selections.push((rest, None));
    selections.push((
        ASYNC_PACKAGES
            .iter()
            .flat_map(|p| ["-p".to_string(), p.to_string()])
            .collect(),
        None,
    ));
    for variant in VARIANTS {
        let mut sel: Vec<String> = VARIANT_PACKAGES
            .iter()
            .flat_map(|(p, _)| ["-p".to_string(), p.to_string()])
            .collect();
        let features: Vec<String> = VARIANT_PACKAGES
            .iter()
            .map(|(p, _)| format!("{p}/{variant}"))
            .collect();
        // Each variant package's default is `full`: the variant is chosen explicitly.
        sel.push("--no-default-features".to_string());
        sel.extend(["--features".to_string(), features.join(",")]);
        selections.push((sel, Some((variant, &VARIANT_PACKAGES[..]))));
    }
    for (variant, feature) in FEATURE_VARIANTS {
        let mut sel: Vec<String> = FEATURE_PACKAGES
            .iter()
            .flat_map(|(p, _)| ["-p".to_string(), p.to_string()])
            .collect();
        let features: Vec<String> = FEATURE_PACKAGES
            .iter()
            .flat_map(|(p, _)| [format!("{p}/lean"), format!("{p}/{feature}")])
            .collect();
        sel.push("--no-default-features".to_string());
        sel.extend(["--features".to_string(), features.join(",")]);
        selections.push((sel, Some((variant, &FEATURE_PACKAGES[..]))));
    }
    for (selection, variant) in selections {
        let mut c = cargo();
        c.current_dir(paths.firmware())
            .arg("build")
            .args(["--profile", profile, "--target", TARGET])
            .arg("--manifest-path")
            .arg(&manifest)
            .arg("--target-dir")
            .arg(&target_dir)
            .args(&selection);
        eprintln!("can-bench: {}", cmd::display(&c));
        cmd::run_ok(&mut c, BUILD_LIMIT).context("building the bench firmware")?;
        if let Some((v, packages)) = variant {
            for (_, bin) in packages {
                let from = out.join(bin);
                let to = out.join(variant_elf(bin, v));
                std::fs::copy(&from, &to).context(format!(
                    "copying {} to {}",
                    from.display(),
                    to.display()
                ))?;
            }
        }
    }
    Ok(out)
}

/// What a variant build leaves to copy: the variant and its (package, binary) pairs.
type Copies = (&'static str, &'static [(&'static str, &'static str)]);

/// The ELF name of `bin` built as `variant`.
pub fn variant_elf(bin: &str, variant: &str) -> String {
    format!("{bin}-{variant}")
}

/// The bench firmware packages built with twocan-core's `async` feature.
pub const ASYNC_PACKAGES: [&str; 2] = ["bench-insn-count-async", "bench-loopback-async"];

/// The variants of issue 21: a **lean** driver configuration (const filter plan,
/// fire-and-forget transmit, no time stamps, no statistics) and a **full** one
/// (completions, time stamps, statistics, runtime planner), each against an equivalent
/// doing the same service. The cargo feature of each package in [`VARIANT_PACKAGES`].
pub const VARIANTS: [&str; 2] = ["lean", "full"];

/// The one-feature variants of issue 21 ("each choice with its own measured cost"):
/// (variant name, cargo feature). Each is `lean` with exactly one per-frame choice
/// switched to its full setting (`bench/firmware/shared/bxcan_variant.rs`): transmit
/// completions, receive time stamps, traffic statistics, filters replaceable while
/// running, the run-time planner (`bench/firmware/shared/flexcan_variant.rs` for
/// FlexCAN). Built for both our drivers ([`FEATURE_PACKAGES`]); the variant name is also
/// what the firmware prints.
pub const FEATURE_VARIANTS: [(&str, &str); 5] = [
    ("lean+done", "done"),
    ("lean+stamps", "stamps"),
    ("lean+counts", "counts"),
    ("lean+switch", "switch"),
    ("lean+planner", "planner"),
];

/// (package, binary) of the bench firmware built once more per one-feature variant of
/// [`FEATURE_VARIANTS`]: our bxCAN and FlexCAN drivers' instruction counts and loop-back
/// firmware (variant packages too, so the `--workspace` build leaves them out).
pub const FEATURE_PACKAGES: [(&str, &str); 4] = [
    ("bench-insn-count", "insn-count"),
    ("bench-loopback-twocan", "loopback-twocan"),
    ("bench-insn-count-flexcan", "insn-count-flexcan"),
    ("bench-loopback-flexcan", "loopback-flexcan"),
];

/// (package, binary) of the bench firmware built once per variant.
pub const VARIANT_PACKAGES: [(&str, &str); 7] = [
    ("bench-insn-count", "insn-count"),
    ("bench-insn-count-equiv", "insn-count-equiv"),
    ("bench-insn-count-flexcan", "insn-count-flexcan"),
    ("bench-loopback-twocan", "loopback-twocan"),
    ("bench-loopback-bxcan-equiv", "loopback-bxcan-equiv"),
    ("bench-loopback-flexcan", "loopback-flexcan"),
    ("bench-loopback-flexcan-hand", "loopback-flexcan-hand"),
];

/// A firmware example package of the workspace, as `cargo metadata` describes it.
#[derive(Debug, Clone)]
pub struct ExamplePackage {
    /// Package name.
    pub name: String,
    /// Folder relative to the workspace root.
    pub dir: String,
    /// Binary targets with their required features.
    pub bins: Vec<(String, Vec<String>)>,
    /// Feature names (without `default`).
    pub features: Vec<String>,
}

/// The firmware packages under `examples/`: those with binary targets and a dependency on
/// `cortex-m-rt` (host examples there, such as a simulation, have none).
pub fn example_packages(paths: &Paths) -> Result<Vec<ExamplePackage>> {
    let mut c = cargo();
    c.current_dir(&paths.root).args([
        "metadata",
        "--no-deps",
        "--format-version",
        "1",
        "--offline",
    ]);
    let out = match cmd::run_ok(&mut c, Duration::from_secs(120)) {
        Ok(o) => o,
        // --offline fails when something is not downloaded yet; try online.
        Err(_) => {
            let mut c = cargo();
            c.current_dir(&paths.root)
                .args(["metadata", "--no-deps", "--format-version", "1"]);
            cmd::run_ok(&mut c, Duration::from_secs(300)).context("cargo metadata")?
        }
    };
    let meta: serde_json::Value =
        serde_json::from_str(&out.stdout).context("parsing cargo metadata")?;
    let examples = paths.root.join("examples");
    let mut found = Vec::new();
    for p in meta["packages"].as_array().into_iter().flatten() {
        let manifest = PathBuf::from(p["manifest_path"].as_str().unwrap_or(""));
        let Some(dir) = manifest.parent() else {
            continue;
        };
        if !dir.starts_with(&examples) {
            continue;
        }
        let bins: Vec<(String, Vec<String>)> = p["targets"]
            .as_array()
            .into_iter()
            .flatten()
            .filter(|t| {
                t["kind"]
                    .as_array()
                    .is_some_and(|k| k.iter().any(|k| k == "bin"))
            })
            .map(|t| {
                let req = t["required-features"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .filter_map(|f| f.as_str().map(String::from))
                    .collect();
                (t["name"].as_str().unwrap_or("?").to_string(), req)
            })
            .collect();
        let firmware = p["dependencies"]
            .as_array()
            .into_iter()
            .flatten()
            .any(|d| d["name"] == "cortex-m-rt");
        if bins.is_empty() || !firmware {
            continue;
        }
        // A board feature selects the chip or board in a dependency (`stm32f7xx-hal/...`,
        // `twocan-flexcan/teensy36`); a feature that enables nothing (a firmware variant
        // such as `bus-250k`) is not a board.
        let features = p["features"]
            .as_object()
            .map(|m| {
                m.iter()
                    .filter(|(k, v)| *k != "default" && v.as_array().is_some_and(|a| !a.is_empty()))
                    .map(|(k, _)| k.clone())
                    .collect()
            })
            .unwrap_or_default();
        found.push(ExamplePackage {
            name: p["name"].as_str().unwrap_or("?").to_string(),
            dir: dir
                .strip_prefix(&paths.root)
                .unwrap_or(dir)
                .display()
                .to_string(),
            bins,
            features,
        });
    }
    found.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(found)
}

/// Builds the binaries of `package` for one feature set (`--release`); returns the ELF
/// directory.
pub fn example(paths: &Paths, package: &str, features: &[String]) -> Result<PathBuf> {
    let target_dir = paths.scratch("bench-examples");
    let target = example_target(features);
    let mut c = cargo();
    c.current_dir(&paths.root)
        .arg("build")
        .args(["--release", "--target", target, "-p", package, "--bins"])
        .arg("--target-dir")
        .arg(&target_dir);
    if !features.is_empty() {
        c.arg("--features").arg(features.join(","));
    }
    eprintln!("can-bench: {}", cmd::display(&c));
    cmd::run_ok(&mut c, BUILD_LIMIT).context(format!("building the example {package}"))?;
    Ok(target_dir.join(target).join("release"))
}

/// Boards whose core is a Cortex-M3 (no FPU, no DSP instructions): their firmware builds
/// for `thumbv7m-none-eabi`; every other board for [`TARGET`].
const CORTEX_M3_BOARDS: &[&str] = &["bluepill"];

/// The target an example builds for with the board `features`.
fn example_target(features: &[String]) -> &'static str {
    if features
        .iter()
        .any(|f| CORTEX_M3_BOARDS.contains(&f.as_str()))
    {
        "thumbv7m-none-eabi"
    } else {
        TARGET
    }
}

/// Builds `can-fil` (the firmware-in-the-loop harness, `fil/`, its own workspace and
/// target directory `fil/target`, shared with its tests); returns the binary.
pub fn can_fil(paths: &Paths) -> Result<PathBuf> {
    let manifest = paths.root.join("fil").join("Cargo.toml");
    let mut c = cargo();
    c.current_dir(paths.root.join("fil"))
        .args(["build", "--release", "--bin", "can-fil", "--manifest-path"])
        .arg(&manifest);
    eprintln!("can-bench: {}", cmd::display(&c));
    cmd::run_ok(&mut c, BUILD_LIMIT).context(
        "building can-fil (fil/: Unicorn needs cmake and libclang, \
         `apt-get install cmake libclang-dev`)",
    )?;
    Ok(paths
        .root
        .join("fil")
        .join("target")
        .join("release")
        .join("can-fil"))
}

/// The version of a package in a Cargo.lock file (`None` if absent).
pub fn locked_version(lock: &Path, package: &str) -> Option<String> {
    let text = std::fs::read_to_string(lock).ok()?;
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        if line.trim() == format!("name = \"{package}\"") {
            let v = lines.next()?.trim();
            return v
                .strip_prefix("version = \"")
                .and_then(|v| v.strip_suffix('"'))
                .map(String::from);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feature_packages_are_variant_packages_and_feature_variants_extend_lean() {
        // The `--workspace` build excludes the variant packages only: a feature package
        // outside them would be built there with its default features.
        for p in FEATURE_PACKAGES {
            assert!(VARIANT_PACKAGES.contains(&p), "{p:?}");
        }
        for (variant, feature) in FEATURE_VARIANTS {
            assert_eq!(variant, format!("lean+{feature}"));
            assert!(!VARIANTS.contains(&variant));
        }
        assert_eq!(
            variant_elf("insn-count", "lean+done"),
            "insn-count-lean+done"
        );
    }
}
