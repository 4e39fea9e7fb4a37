//! `can-bench`: the benchmark command of twocan.
//!
//! ```sh
//! cargo run --release --bin can-bench
//! ```
//!
//! It measures, in one run, and writes `docs/benchmarks.md` (also printed):
//!
//! 1. flash and RAM of the firmware examples and of minimal loop-back firmwares — our
//!    bxCAN and FlexCAN drivers in a lean and a full variant (and our bxCAN driver in
//!    one-feature variants: lean with one choice switched to full, for each choice's
//!    own cost), the `bxcan` crate 0.8 bare and with the service that makes it
//!    feature-equivalent, a hand-written FlexCAN service ([`sizes`], [`firmware`]);
//!    the examples' stack under `can-fil --stack` ([`stack`]);
//! 2. instructions per frame and stack high-water marks on a Cortex-M4 under QEMU,
//!    counted by the TCG plugin `bench/plugin/insn_count.c` ([`qemu`]);
//! 3. the bit-timing solver against an exhaustive search ([`timing`]);
//! 4. the simulator's speed ([`simspeed`], [`models`]).
//!
//! With the sizes and the instruction counts measured it also writes
//! `target/bench/summary.json`: the ratios ours / theirs of issues 10 and 21 as numbers,
//! for scripts (see [`report::Report::summary`], [`figures`]).
//!
//! Any step that cannot run ends the command with an error and a non-zero exit code,
//! without touching `docs/benchmarks.md`. `--skip STEP` (sizes, examples, fil, qemu,
//! timing, sim; repeatable) leaves a step out for a quicker look: the tables are
//! printed, the document is not written.
//!
//! can-bench installs nothing by itself: a missing tool (QEMU, gcc, the
//! `thumbv7em-none-eabihf` target) ends it with a message naming the tool and how to get
//! it. With `--install` it installs them (Debian packages with apt-get when run as root,
//! the target with rustup).

mod cmd;
mod figures;
mod firmware;
mod models;
mod planner;
mod qemu;
mod report;
mod simspeed;
mod sizes;
mod stack;
mod timing;

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::{Parser, ValueEnum};

use cmd::{Context, Result};
use figures::Backend;
use firmware::Paths;
use firmware::{variant_elf, FEATURE_VARIANTS, VARIANTS};
use report::{
    ExampleBuild, ExampleSection, InsnRun, InsnSection, LoopbackStack, Report, SizeBuild,
    SizeSection, StateSet, VariantSizes,
};
use simspeed::SimRow;

/// A step of the command, for `--skip`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Step {
    /// flash and RAM of the loop-back firmwares
    Sizes,
    /// flash and RAM of the firmware examples
    Examples,
    /// the firmware examples' stack under can-fil (needs the examples step)
    Fil,
    /// instructions per frame under QEMU
    Qemu,
    /// bit-timing quality
    Timing,
    /// simulator speed
    Sim,
}

impl Step {
    fn name(self) -> &'static str {
        match self {
            Step::Sizes => "sizes",
            Step::Examples => "examples",
            Step::Fil => "fil",
            Step::Qemu => "qemu",
            Step::Timing => "timing",
            Step::Sim => "sim",
        }
    }
}

/// can-bench: measures twocan and writes docs/benchmarks.md (a run with --skip prints the
/// tables and does not write the document).
#[derive(Debug, Parser)]
#[command(name = "can-bench", version)]
struct Args {
    /// Leave a step out (repeatable)
    #[arg(long, value_enum, value_name = "STEP")]
    skip: Vec<Step>,
    /// Install what is missing (QEMU and gcc with apt-get, as root; the
    /// thumbv7em-none-eabihf target with rustup) instead of stopping with a message
    #[arg(long)]
    install: bool,
}

/// The variant loop-back firmwares and the board can-fil runs each on.
const LOOPBACK_BOARDS: [(&str, &str); 4] = [
    ("loopback-twocan", "nucleo-f767zi"),
    ("loopback-bxcan-equiv", "nucleo-f767zi"),
    ("loopback-flexcan", "teensy36"),
    ("loopback-flexcan-hand", "teensy36"),
];

/// Profiles of the bench firmware (sizes and instruction counts): (cargo profile, opt-level).
const COUNT_PROFILES: [(&str, &str); 2] = [("release", "s"), ("release-speed", "3")];

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("can-bench: error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn step(name: &str) {
    eprintln!("\ncan-bench: ==> {name}");
}

/// Prints how long the steps so far took.
fn lap(started: Instant) {
    eprintln!("can-bench: ({:.1} s)", started.elapsed().as_secs_f64());
}

fn run() -> Result<()> {
    // Bad options: clap prints the error and a usage line and exits with status 2.
    let args = Args::parse();
    let skip: Vec<&str> = args.skip.iter().map(|s| s.name()).collect();
    let skipped = |s: &str| skip.contains(&s);
    let started = Instant::now();
    let paths = Paths::discover()?;
    let mut report = Report::new(&paths);
    // QEMU and gcc first: a missing tool should stop the command before the long builds.
    let tools = if skipped("qemu") {
        None
    } else {
        step("tools for the instruction counts (QEMU, gcc)");
        let t = qemu::tools(args.install)?;
        eprintln!("can-bench: {}; {}", t.qemu_version, t.gcc_version);
        Some(t)
    };

    if !skipped("timing") {
        lap(started);
        step("bit-timing quality (solver against exhaustive search)");
        report.timing = Some(vec![
            timing::run("FlexCAN", &twocan_core::timing::Limits::FLEXCAN),
            timing::run("bxCAN", &twocan_core::timing::Limits::BXCAN),
        ]);
    }

    if !skipped("sim") {
        lap(started);
        step("simulator speed");
        let mut speeds = Vec::new();
        for (senders, tracing) in [(1, false), (1, true), (4, false)] {
            speeds.push(SimRow::run(|fast| {
                simspeed::bare_bus(senders, tracing, fast)
            })?);
        }
        speeds.push(SimRow::run(models::two_drivers)?);
        speeds.push(SimRow::run(models::harness)?);
        for r in &speeds {
            eprintln!(
                "can-bench: {}: {:.0} frames/s, bit-level path {:.0} frames/s, ratio {:.2} \
                 (medians of {})",
                r.fast.scenario(),
                r.fast.median().frames_per_sec(),
                r.bit_level.median().frames_per_sec(),
                r.ratio(),
                r.fast.runs.len()
            );
        }
        report.sim = Some(speeds);
    }

    let need_firmware = !skipped("sizes") || !skipped("qemu");
    let mut firmware_dirs: Vec<(String, PathBuf)> = Vec::new();
    if need_firmware || !skipped("examples") {
        firmware::ensure_target(args.install)?;
    }
    if need_firmware {
        lap(started);
        step("bench firmware (bench/firmware)");
        for (profile, _) in COUNT_PROFILES {
            let t = Instant::now();
            let dir = firmware::bench_firmware(&paths, profile)?;
            report.build_secs += t.elapsed().as_secs_f64();
            firmware_dirs.push((profile.to_string(), dir));
        }
    }

    // can-fil (fil/, Unicorn) runs the loop-back firmwares (checked, stack) and the
    // examples (stack).
    let can_fil = if skipped("fil") {
        None
    } else {
        lap(started);
        step("can-fil (fil/), for the stacks and the loop-back check");
        let t = Instant::now();
        let f = firmware::can_fil(&paths)?;
        report.build_secs += t.elapsed().as_secs_f64();
        Some(f)
    };

    if !skipped("sizes") {
        lap(started);
        step("flash and RAM of the loop-back firmwares");
        let mut builds = Vec::new();
        for ((profile, opt), (_, dir)) in COUNT_PROFILES.iter().zip(&firmware_dirs) {
            let mut variants = Vec::new();
            for v in VARIANTS {
                let elf = |bin: &str| dir.join(variant_elf(bin, v));
                variants.push(VariantSizes {
                    variant: v.to_string(),
                    ours: sizes::measure(&elf("loopback-twocan"))?,
                    equiv: sizes::measure(&elf("loopback-bxcan-equiv"))?,
                    flexcan: sizes::measure(&elf("loopback-flexcan"))?,
                    flexcan_hand: sizes::measure(&elf("loopback-flexcan-hand"))?,
                });
            }
            let mut features = Vec::new();
            for backend in Backend::ALL {
                for (v, _) in FEATURE_VARIANTS {
                    let elf = dir.join(variant_elf(backend.loopback(), v));
                    features.push((backend, v.to_string(), sizes::measure(&elf)?));
                }
            }
            builds.push(SizeBuild {
                profile: profile.to_string(),
                opt: opt.to_string(),
                bare: sizes::measure(&dir.join("loopback-bxcan"))?,
                async_fw: sizes::measure(&dir.join("loopback-async"))?,
                variants,
                features,
            });
        }
        let dir = &firmware_dirs[0].1;
        let mut states = Vec::new();
        for v in VARIANTS {
            let elf = |bin: &str| dir.join(variant_elf(bin, v));
            let set = StateSet {
                variant: v.to_string(),
                bxcan: sizes::state_figures(&elf("loopback-twocan"), &elf("insn-count"))?,
                flexcan: sizes::state_figures(
                    &elf("loopback-flexcan"),
                    &elf("insn-count-flexcan"),
                )?,
            };
            eprintln!(
                "can-bench: {v}: bxCAN State {} B = rings {} B + state {} B; FlexCAN State \
                 {} B = rings {} B + state {} B",
                set.bxcan.static_bytes,
                set.bxcan.ring_bytes,
                set.bxcan.state_bytes(),
                set.flexcan.static_bytes,
                set.flexcan.ring_bytes,
                set.flexcan.state_bytes()
            );
            states.push(set);
        }
        let mut feature_states = Vec::new();
        for backend in Backend::ALL {
            for (v, _) in FEATURE_VARIANTS {
                let elf = |bin: &str| dir.join(variant_elf(bin, v));
                let st = sizes::state_figures(&elf(backend.loopback()), &elf(backend.firmware()))?;
                eprintln!(
                    "can-bench: {v}: {} State {} B = rings {} B + state {} B",
                    backend.name(),
                    st.static_bytes,
                    st.ring_bytes,
                    st.state_bytes()
                );
                feature_states.push((backend, v.to_string(), st));
            }
        }
        let mut fil = Vec::new();
        if let Some(can_fil) = &can_fil {
            step("the loop-back firmwares under can-fil (they must work; their stack)");
            for ((_, opt), (_, dir)) in COUNT_PROFILES.iter().zip(&firmware_dirs) {
                let mut elfs: Vec<(String, &str)> = vec![
                    ("loopback-bxcan".into(), "nucleo-f767zi"),
                    ("loopback-async".into(), "nucleo-f767zi"),
                ];
                for v in VARIANTS {
                    for (bin, board) in LOOPBACK_BOARDS {
                        elfs.push((variant_elf(bin, v), board));
                    }
                }
                for backend in Backend::ALL {
                    for (v, _) in FEATURE_VARIANTS {
                        elfs.push((variant_elf(backend.loopback(), v), backend.board()));
                    }
                }
                for (elf, board) in elfs {
                    let st = stack::measure_loopback(can_fil, board, &dir.join(&elf))?;
                    eprintln!(
                        "can-bench: {elf} (opt {opt}) on {board}: works, stack {} B",
                        st.whole
                    );
                    fil.push(LoopbackStack {
                        opt: opt.to_string(),
                        elf,
                        board: board.to_string(),
                        stack: st,
                    });
                }
            }
        }
        report.sizes = Some(SizeSection {
            builds,
            states,
            feature_states,
            fil,
        });
    }

    if !skipped("examples") {
        lap(started);
        step("flash and RAM of the firmware examples");
        let t = Instant::now();
        let mut section = examples(&paths)?;
        report.build_secs += t.elapsed().as_secs_f64();
        if let Some(can_fil) = &can_fil {
            lap(started);
            step("stack of the firmware examples under can-fil");
            for b in &mut section.builds {
                let Some(board) = &b.board else { continue };
                let st = stack::measure(can_fil, fil_profile(board), &b.elf)?;
                eprintln!(
                    "can-bench: {} on {board}: stack configuration {:?} B, whole run {} B",
                    b.bin, st.configuration, st.whole
                );
                b.stack = Some(st);
            }
        } else {
            section.stack_skipped = Some("`--skip fil`".into());
        }
        report.examples = Some(section);
    }

    if let Some(tools) = tools {
        lap(started);
        step("instructions per frame and stack under QEMU");
        let plugin = qemu::build_plugin(&paths, &tools)?;
        let mut runs = Vec::new();
        for ((profile, opt), (_, dir)) in COUNT_PROFILES.iter().zip(&firmware_dirs) {
            for backend in Backend::ALL {
                for v in VARIANTS {
                    let mut counts: Option<qemu::Counts> = None;
                    for fw in backend.images() {
                        let elf = dir.join(variant_elf(fw, v));
                        let tag = format!("{profile}-{fw}-{v}");
                        let c = qemu::run(&paths, &tools, &plugin, &elf, &tag)
                            .context(format!("{fw} {v} ({profile} profile)"))?;
                        if c.variant.as_deref() != Some(v) {
                            return Err(cmd::Error::new(format!(
                                "{} says it is variant {:?}, built as {v}",
                                elf.display(),
                                c.variant
                            )));
                        }
                        match &mut counts {
                            None => counts = Some(c),
                            Some(all) => all.merge(c)?,
                        }
                    }
                    let Some(counts) = counts else { continue };
                    runs.push(InsnRun {
                        backend,
                        variant: v.to_string(),
                        opt: opt.to_string(),
                        counts,
                    });
                }
            }
        }
        // The one-feature variants of our drivers: `insn-count` and `insn-count-flexcan`
        // alone (their cost is against lean, not against an equivalent).
        let mut feature_runs = Vec::new();
        for ((profile, opt), (_, dir)) in COUNT_PROFILES.iter().zip(&firmware_dirs) {
            for backend in Backend::ALL {
                for (v, _) in FEATURE_VARIANTS {
                    let fw = backend.firmware();
                    let elf = dir.join(variant_elf(fw, v));
                    let tag = format!("{profile}-{fw}-{v}");
                    let counts = qemu::run(&paths, &tools, &plugin, &elf, &tag)
                        .context(format!("{fw} {v} ({profile} profile)"))?;
                    if counts.variant.as_deref() != Some(v) {
                        return Err(cmd::Error::new(format!(
                            "{} says it is variant {:?}, built as {v}",
                            elf.display(),
                            counts.variant
                        )));
                    }
                    feature_runs.push(InsnRun {
                        backend,
                        variant: v.to_string(),
                        opt: opt.to_string(),
                        counts,
                    });
                }
            }
        }
        let mut async_runs = Vec::new();
        for ((profile, opt), (_, dir)) in COUNT_PROFILES.iter().zip(&firmware_dirs) {
            let elf = dir.join("insn-count-async");
            let tag = format!("{profile}-async");
            let counts = qemu::run(&paths, &tools, &plugin, &elf, &tag)
                .context(format!("async instruction counts ({profile} profile)"))?;
            async_runs.push((opt.to_string(), counts));
        }
        let window = sizes::read_u32_symbol(
            &firmware_dirs[0].1.join(variant_elf("insn-count", "lean")),
            "BENCH_MARKER_WINDOW",
        )?;
        report.insn = Some(InsnSection {
            tools,
            runs,
            feature_runs,
            async_runs,
            window,
        });
    }

    lap(started);
    report.elapsed_secs = started.elapsed().as_secs_f64();
    if let Some(summary) = report.summary()? {
        let dir = paths.scratch("bench");
        std::fs::create_dir_all(&dir).context(format!("creating {}", dir.display()))?;
        let path = dir.join("summary.json");
        let json = serde_json::to_string_pretty(&summary).context("summary.json")?;
        std::fs::write(&path, json + "\n").context(format!("writing {}", path.display()))?;
        eprintln!("can-bench: wrote {}", path.display());
    }
    eprintln!("can-bench: ==> filter planner quality on the identifier corpus");
    let text = report.render()? + "\n" + &planner::report();
    println!("{text}");
    if skip.is_empty() {
        let path = paths.root.join("docs").join("benchmarks.md");
        std::fs::write(&path, &text).context(format!("writing {}", path.display()))?;
        eprintln!(
            "can-bench: wrote {} ({:.0} s)",
            path.display(),
            report.elapsed_secs
        );
    } else {
        eprintln!(
            "can-bench: steps skipped ({}): docs/benchmarks.md not written",
            skip.join(", ")
        );
    }
    Ok(())
}

/// The `can-fil` board profile a board feature's images run on: the Teensy 4.0 on the
/// `teensy41` profile (one chip, the i.MX RT1062; the 4.0's image differs in the flash
/// size its boot header states), every other board on its own.
fn fil_profile(board: &str) -> &str {
    match board {
        "teensy40" => "teensy41",
        b => b,
    }
}

/// Features that select something other than a board.
const NOT_BOARDS: [&str; 5] = ["defmt", "std", "log", "model", "mock"];

fn examples(paths: &Paths) -> Result<ExampleSection> {
    let packages = firmware::example_packages(paths)?;
    if packages.is_empty() {
        eprintln!(
            "can-bench: no firmware example under examples/ yet (no package with binaries \
             and a cortex-m-rt dependency): nothing to measure there"
        );
        return Ok(ExampleSection {
            builds: Vec::new(),
            stack_skipped: None,
        });
    }
    let mut builds = Vec::new();
    for p in &packages {
        let boards: Vec<Option<String>> = {
            let b: Vec<_> = p
                .features
                .iter()
                .filter(|f| !NOT_BOARDS.contains(&f.as_str()))
                .cloned()
                .map(Some)
                .collect();
            if b.is_empty() {
                vec![None]
            } else {
                b
            }
        };
        for board in boards {
            let features: Vec<String> = board.iter().cloned().collect();
            let dir = firmware::example(paths, &p.name, &features)?;
            for (bin, required) in &p.bins {
                if !required.iter().all(|r| features.contains(r)) {
                    continue;
                }
                // The boards of a package build binaries of the same name: each ELF is
                // kept under its board's name (for can-fil after all builds).
                let kept = paths
                    .scratch("bench-examples")
                    .join("elf")
                    .join(board.as_deref().unwrap_or("no-feature"));
                std::fs::create_dir_all(&kept).context(format!("creating {}", kept.display()))?;
                let elf = kept.join(bin);
                std::fs::copy(dir.join(bin), &elf)
                    .context(format!("copying {bin} to {}", elf.display()))?;
                let size = sizes::measure(&elf).context(format!(
                    "{} {bin} ({})",
                    p.name,
                    features.join(",")
                ))?;
                builds.push(ExampleBuild {
                    package: p.name.clone(),
                    dir: p.dir.clone(),
                    board: board.clone(),
                    bin: bin.clone(),
                    elf,
                    size,
                    stack: None,
                });
            }
        }
    }
    Ok(ExampleSection {
        builds,
        stack_skipped: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn teensy40_images_run_on_the_rt1062_profile() {
        assert_eq!(fil_profile("teensy40"), "teensy41");
        assert_eq!(fil_profile("teensy36"), "teensy36");
    }

    #[test]
    fn options() {
        let a = Args::try_parse_from(["can-bench", "--skip", "qemu", "--skip=sim", "--install"])
            .unwrap();
        assert_eq!(a.skip, [Step::Qemu, Step::Sim]);
        assert!(a.install);
        let a = Args::try_parse_from(["can-bench"]).unwrap();
        assert!(a.skip.is_empty() && !a.install);
        assert!(Args::try_parse_from(["can-bench", "--skip", "frob"]).is_err());
        assert!(Args::try_parse_from(["can-bench", "--install=yes"]).is_err());
        assert_eq!(
            [
                Step::Sizes,
                Step::Examples,
                Step::Fil,
                Step::Qemu,
                Step::Timing,
                Step::Sim
            ]
            .map(Step::name),
            ["sizes", "examples", "fil", "qemu", "timing", "sim"]
        );
        Args::command().debug_assert();
    }
}
