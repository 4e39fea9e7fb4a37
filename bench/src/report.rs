//! `docs/benchmarks.md`: every figure of one run, with the machine, the tools and the
//! method behind each. The issue-21 targets and `summary.json` come from
//! [`crate::figures`].

use std::fmt::Write as _;

use crate::cmd::{self, Result};
use crate::figures::{self, step_of, Backend, FeatureCost, Figures, Measured};
use crate::firmware::{self, Paths, TARGET, VARIANTS};
use crate::qemu::{self, Counts, Tools};
use crate::simspeed::{self, SimRow};
use crate::sizes::{Size, StateFigures};
use crate::stack::FilStack;
use crate::timing::{self, Case, ControllerQuality};

/// The loop-back firmwares of one variant, one build profile.
pub struct VariantSizes {
    /// `lean` or `full`.
    pub variant: String,
    /// `loopback-twocan` (our bxCAN driver).
    pub ours: Size,
    /// `loopback-bxcan-equiv` (the `bxcan` crate and the service of the variant).
    pub equiv: Size,
    /// `loopback-flexcan` (our FlexCAN driver).
    pub flexcan: Size,
    /// `loopback-flexcan-hand` (the hand-written FlexCAN service).
    pub flexcan_hand: Size,
}

impl VariantSizes {
    /// Our loop-back firmware of `backend` and its equivalent's.
    pub fn of(&self, backend: Backend) -> (&Size, &Size) {
        match backend {
            Backend::BxCan => (&self.ours, &self.equiv),
            Backend::FlexCan => (&self.flexcan, &self.flexcan_hand),
        }
    }
}

/// The loop-back comparison of one build profile.
pub struct SizeBuild {
    /// Cargo profile.
    pub profile: String,
    /// Its opt-level.
    pub opt: String,
    /// `loopback-bxcan` (the bare `bxcan` crate).
    pub bare: Size,
    /// `loopback-async` (our driver through its async API, full features).
    pub async_fw: Size,
    /// Per variant.
    pub variants: Vec<VariantSizes>,
    /// Our loop-back firmware per backend and one-feature variant
    /// (`firmware::FEATURE_VARIANTS`): (backend, variant, size).
    pub features: Vec<(Backend, String, Size)>,
}

impl SizeBuild {
    /// The firmwares of `variant`.
    pub fn variant(&self, variant: &str) -> Option<&VariantSizes> {
        self.variants.iter().find(|v| v.variant == variant)
    }
}

/// What our drivers' `State` statics hold, per variant.
pub struct StateSet {
    /// `lean` or `full`.
    pub variant: String,
    /// bxCAN (`loopback-twocan` with `insn-count`).
    pub bxcan: StateFigures,
    /// FlexCAN (`loopback-flexcan` with `insn-count-flexcan`).
    pub flexcan: StateFigures,
}

impl StateSet {
    /// The figures of `backend`'s driver.
    pub fn of(&self, backend: Backend) -> &StateFigures {
        match backend {
            Backend::BxCan => &self.bxcan,
            Backend::FlexCan => &self.flexcan,
        }
    }
}

/// A loop-back firmware run under `can-fil --stack`.
pub struct LoopbackStack {
    /// Opt-level of its build.
    pub opt: String,
    /// Its ELF name (`loopback-twocan-lean` ...).
    pub elf: String,
    /// The board can-fil emulated.
    pub board: String,
    /// Its stack over the run.
    pub stack: FilStack,
}

/// The loop-back comparison.
pub struct SizeSection {
    /// One comparison per profile (the first is the headline).
    pub builds: Vec<SizeBuild>,
    /// State figures per variant (size-optimised build).
    pub states: Vec<StateSet>,
    /// Our drivers' state figures per one-feature variant (size-optimised build):
    /// (backend, variant, figures).
    pub feature_states: Vec<(Backend, String, StateFigures)>,
    /// The loop-back firmwares under can-fil (empty with `--skip fil`).
    pub fil: Vec<LoopbackStack>,
}

impl SizeSection {
    /// The build of `opt`.
    pub fn build(&self, opt: &str) -> Option<&SizeBuild> {
        self.builds.iter().find(|b| b.opt == opt)
    }

    /// The state figures of `variant`.
    pub fn state(&self, variant: &str) -> Option<&StateSet> {
        self.states.iter().find(|s| s.variant == variant)
    }
}

/// One built example binary.
pub struct ExampleBuild {
    /// Package.
    pub package: String,
    /// Its folder.
    pub dir: String,
    /// Board feature (`None`: built without features).
    pub board: Option<String>,
    /// Binary.
    pub bin: String,
    /// The ELF.
    pub elf: std::path::PathBuf,
    /// Its memory use.
    pub size: Size,
    /// Its stack under `can-fil --stack` (`None`: not run on can-fil).
    pub stack: Option<FilStack>,
}

/// The firmware examples.
pub struct ExampleSection {
    /// Every binary built.
    pub builds: Vec<ExampleBuild>,
    /// Why the stacks were not measured, when they were not.
    pub stack_skipped: Option<String>,
}

/// One run of an instruction-count firmware.
pub struct InsnRun {
    /// Which backend's firmware (`insn-count` or `insn-count-flexcan`).
    pub backend: Backend,
    /// `lean` or `full`.
    pub variant: String,
    /// Opt-level of its build.
    pub opt: String,
    /// What it measured.
    pub counts: Counts,
}

/// The instruction counts.
pub struct InsnSection {
    /// QEMU and gcc.
    pub tools: Tools,
    /// Every run.
    pub runs: Vec<InsnRun>,
    /// The runs of `insn-count` and `insn-count-flexcan` per one-feature variant
    /// (`firmware::FEATURE_VARIANTS`, our drivers alone).
    pub feature_runs: Vec<InsnRun>,
    /// (opt-level, counts) of `insn-count-async` per build.
    pub async_runs: Vec<(String, Counts)>,
    /// The marker window address.
    pub window: u32,
}

impl InsnSection {
    /// The counts of `backend`, `variant`, `opt`.
    pub fn get(&self, backend: Backend, variant: &str, opt: &str) -> Result<&Counts> {
        self.runs
            .iter()
            .find(|r| r.backend == backend && r.variant == variant && r.opt == opt)
            .map(|r| &r.counts)
            .ok_or_else(|| {
                cmd::Error::new(format!(
                    "no {} {variant} run at opt {opt}",
                    backend.firmware()
                ))
            })
    }

    /// The counts of `backend`'s firmware built as the one-feature variant `variant`,
    /// at `opt`.
    pub fn get_feature(&self, backend: Backend, variant: &str, opt: &str) -> Result<&Counts> {
        self.feature_runs
            .iter()
            .find(|r| r.backend == backend && r.variant == variant && r.opt == opt)
            .map(|r| &r.counts)
            .ok_or_else(|| {
                cmd::Error::new(format!(
                    "no {} {variant} run at opt {opt}",
                    backend.firmware()
                ))
            })
    }

    /// The opt-levels measured, in build order.
    pub fn opts(&self) -> Vec<String> {
        let mut v: Vec<String> = Vec::new();
        for r in &self.runs {
            if !v.contains(&r.opt) {
                v.push(r.opt.clone());
            }
        }
        v
    }
}

/// Everything measured.
pub struct Report {
    paths: Paths,
    /// Loop-back sizes.
    pub sizes: Option<SizeSection>,
    /// Example sizes (and stacks).
    pub examples: Option<ExampleSection>,
    /// Instruction counts.
    pub insn: Option<InsnSection>,
    /// Bit-timing quality per controller.
    pub timing: Option<Vec<ControllerQuality>>,
    /// Simulator speed.
    pub sim: Option<Vec<SimRow>>,
    /// Wall time of the whole run, seconds.
    pub elapsed_secs: f64,
    /// Of which cargo builds of firmware (short when they were already built).
    pub build_secs: f64,
}

/// `1234567` → `1,234,567`.
pub(crate) fn thousands(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

fn ratio(a: u64, b: u64) -> String {
    if b == 0 {
        "–".into()
    } else {
        format!("{:.2}", a as f64 / b as f64)
    }
}

fn rate(r: u32) -> String {
    if r >= 1_000_000 && r.is_multiple_of(1_000_000) {
        format!("{} Mbit/s", r / 1_000_000)
    } else if r.is_multiple_of(1000) {
        format!("{} kbit/s", r / 1000)
    } else {
        format!("{} bit/s", thousands(r as u64))
    }
}

fn mhz(clock: u32) -> String {
    format!("{} MHz", clock / 1_000_000)
}

fn machine() -> Vec<(&'static str, String)> {
    let os = std::fs::read_to_string("/etc/os-release")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("PRETTY_NAME="))
                .map(|v| v.trim_matches('"').to_string())
        })
        .unwrap_or_else(|| "unknown".into());
    let kernel = cmd::first_line("uname", &["-srm"]).unwrap_or_else(|| "unknown".into());
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|v| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into());
    let cores = std::thread::available_parallelism()
        .map(|n| n.get().to_string())
        .unwrap_or_else(|_| "?".into());
    let version = |p: &str| cmd::first_line(p, &["-V"]).unwrap_or_else(|| "not found".into());
    vec![
        ("operating system", format!("{os}, {kernel}")),
        ("CPU", format!("{cpu}, {cores} logical cores available")),
        ("rustc", version("rustc")),
        (
            "cargo",
            std::env::var("CARGO")
                .ok()
                .and_then(|c| cmd::first_line(&c, &["-V"]))
                .unwrap_or_else(|| version("cargo")),
        ),
    ]
}

impl Report {
    /// An empty report.
    pub fn new(paths: &Paths) -> Self {
        Report {
            paths: paths.clone(),
            sizes: None,
            examples: None,
            insn: None,
            timing: None,
            sim: None,
            elapsed_secs: 0.0,
            build_secs: 0.0,
        }
    }

    /// The issue-21 figures, when both the sizes and the instruction counts were
    /// measured.
    pub fn figures(&self) -> Result<Option<Figures>> {
        match (&self.insn, &self.sizes) {
            (Some(insn), Some(sizes)) => {
                Ok(Some(Figures::compute(insn, sizes, self.examples.as_ref())?))
            }
            _ => Ok(None),
        }
    }

    fn render_async(&self, s: &mut String, insn: &InsnSection) -> Result<()> {
        let _ = writeln!(s, "### Async receive path (issue 11)\n");
        let _ = writeln!(
            s,
            "`bench/firmware/insn-count-async`: our bxCAN driver (completions, time stamps \
             off, filters set by hand) on the same register stand-in, built with \
             twocan-core's `async` feature (a cargo invocation of its own, so the feature \
             does not reach the other firmwares). One frame through the async API as an \
             executor drives it: the task polls its `Rx::recv` future on an empty ring (it \
             registers its waker: `Pending`), the RX0 handler moves one frame into the \
             ring and wakes the waker, the task polls again and gets the frame with its \
             filter index (`Ready`). The waker is a flag and the executor a hand-rolled \
             poll, so what an executor adds around a wake (queueing the task) is not \
             counted. `Rx::receive` in the same build shows the non-async take.\n"
        );
        let mut header = String::from("| step | what is measured |");
        let mut rule = String::from("|---|---|");
        for (opt, _) in &insn.async_runs {
            let _ = write!(header, " opt {opt} |");
            rule.push_str("---:|");
        }
        let _ = writeln!(s, "{header}\n{rule}");
        let rows: [(&str, &str, &[&str]); 5] = [
            (
                "1",
                "`Rx::recv` polled, ring empty → `Pending` (waker registered)",
                &["async.recv.pending"],
            ),
            (
                "2",
                "RX0 handler: one frame into the ring, waker woken",
                &["async.rx_irq"],
            ),
            (
                "3",
                "`Rx::recv` polled again → `Ready(frame)`",
                &["async.recv.ready"],
            ),
            (
                "**1 + 2 + 3**",
                "**the async receive path per frame**",
                &["async.recv.pending", "async.rx_irq", "async.recv.ready"],
            ),
            (
                "–",
                "`Rx::receive` (same build, no future)",
                &["async.receive"],
            ),
        ];
        for (step, what, keys) in rows {
            let mut line = format!("| {step} | {what} |");
            for (_, counts) in &insn.async_runs {
                let _ = write!(line, " {} |", thousands(sum(counts, keys)?));
            }
            let _ = writeln!(s, "{line}");
        }
        let _ = writeln!(s);
        let sync: Vec<String> = insn
            .runs
            .iter()
            .filter(|r| r.backend == Backend::BxCan)
            .map(|r| {
                Ok(format!(
                    "{} ({}, opt {})",
                    thousands(sum(&r.counts, &["twocan.rx_irq", "twocan.rx.receive"])?),
                    r.variant,
                    r.opt
                ))
            })
            .collect::<Result<_>>()?;
        let _ = writeln!(
            s,
            "For comparison, the same frame without the async feature (RX0 handler + \
             `Rx::receive`, `insn-count`): {}.\n",
            sync.join(", ")
        );
        if let Some(sz) = &self.sizes {
            let _ = writeln!(
                s,
                "Flash of an async firmware: `bench/firmware/loopback-async` (the loop-back \
                 firmware of section 1 with `Tx::send`, `Rx::recv` and `Tx::completed` \
                 polled by a hand-rolled loop with the flag waker; no executor crate):"
            );
            for b in &sz.builds {
                let full = b.variant("full").map(|v| v.ours.flash()).unwrap_or(0);
                let _ = writeln!(
                    s,
                    "- opt {}: flash **{}** B (RAM {} B), against {} B for the non-async \
                     `loopback-twocan` (full);",
                    b.opt,
                    thousands(b.async_fw.flash()),
                    thousands(b.async_fw.ram()),
                    thousands(full)
                );
            }
            let echo: Vec<String> = self
                .examples
                .iter()
                .flat_map(|e| e.builds.iter())
                .filter(|b| b.bin.ends_with("async-echo"))
                .map(|b| {
                    format!(
                        "`{}` ({}): flash **{}** B, RAM {} B",
                        b.bin,
                        b.board.as_deref().unwrap_or("no feature"),
                        thousands(b.size.flash()),
                        thousands(b.size.ram())
                    )
                })
                .collect();
            if echo.is_empty() {
                let _ = writeln!(
                    s,
                    "- the `async-echo` firmware examples were not among the examples built \
                     in this run (section 1, \"Firmware examples\"), so their flash is not \
                     given here.\n"
                );
            } else {
                let _ = writeln!(s, "- the `async-echo` examples: {}.\n", echo.join("; "));
            }
        }
        Ok(())
    }

    /// `target/bench/summary.json`: the ratios ours / theirs as floats and byte figures
    /// as integers; `None` unless both the sizes and the instruction counts (opt s and
    /// opt 3) were measured.
    ///
    /// The fields of issue 10 keep their names and now describe the **full** variant
    /// (the one with every feature, as the single firmware of issue 10 had):
    /// `tx_ratio_*` (direct transmit / `Can::transmit`), `rx_isr_ratio_*` (RX0 handler /
    /// bare `Rx0::receive`), `roundtrip_ratio_*` (round trip / the feature-equivalent
    /// service), `flash_ratio_equiv_s` and `flash_ratio_bare_s` (whole flash),
    /// `ram_state_bytes`, `ram_ring_bytes`. The fields of issue 21 follow
    /// ([`Figures::summary_fields`]).
    pub fn summary(&self) -> Result<Option<serde_json::Value>> {
        let (Some(sizes), Some(insn), Some(fig)) = (&self.sizes, &self.insn, self.figures()?)
        else {
            return Ok(None);
        };
        let (Some(size_s), Some(full_state)) = (sizes.build("s"), sizes.state("full")) else {
            return Ok(None);
        };
        let Some(full_s) = size_s.variant("full") else {
            return Ok(None);
        };
        let b = Backend::BxCan;
        let v = |key: &str, opt: &str| fig.value(b, "full", key, opt);
        let mut counts = serde_json::Map::new();
        for r in insn
            .runs
            .iter()
            .filter(|r| r.backend == b && r.variant == "full")
        {
            for (tag, ours, theirs) in [
                ("a", "twocan.tx.direct", "bxcan.transmit"),
                ("b", "twocan.rx_irq", "bxcan.rx0.receive"),
            ] {
                counts.insert(
                    format!("{tag}_ours_{}", r.opt),
                    r.counts.net(ours)?.0.into(),
                );
                counts.insert(
                    format!("{tag}_theirs_{}", r.opt),
                    r.counts.net(theirs)?.0.into(),
                );
            }
            counts.insert(
                format!("c_ours_{}", r.opt),
                r.counts.roundtrip("twocan")?.into(),
            );
            counts.insert(
                format!("c_theirs_{}", r.opt),
                r.counts.roundtrip("equiv")?.into(),
            );
        }
        let mut m = serde_json::Map::new();
        m.insert("tx_ratio_s".into(), v("tx", "s")?.into());
        m.insert("tx_ratio_3".into(), v("tx", "3")?.into());
        m.insert("rx_isr_ratio_s".into(), v("rx_bare", "s")?.into());
        m.insert("rx_isr_ratio_3".into(), v("rx_bare", "3")?.into());
        m.insert("roundtrip_ratio_s".into(), v("roundtrip", "s")?.into());
        m.insert("roundtrip_ratio_3".into(), v("roundtrip", "3")?.into());
        m.insert(
            "flash_ratio_equiv_s".into(),
            ratio_f(full_s.ours.flash(), full_s.equiv.flash()).into(),
        );
        m.insert(
            "flash_ratio_bare_s".into(),
            ratio_f(full_s.ours.flash(), size_s.bare.flash()).into(),
        );
        m.insert(
            "ram_state_bytes".into(),
            full_state.bxcan.state_bytes().into(),
        );
        m.insert("ram_ring_bytes".into(), full_state.bxcan.ring_bytes.into());
        m.insert(
            "flash_bytes_s".into(),
            serde_json::json!({
                "twocan": full_s.ours.flash(),
                "bxcan": size_s.bare.flash(),
                "bxcan_equiv": full_s.equiv.flash(),
            }),
        );
        m.insert("instructions".into(), serde_json::Value::Object(counts));
        m.insert(
            "async_rx_path".into(),
            serde_json::Value::Object(
                insn.async_runs
                    .iter()
                    .map(|(opt, c)| {
                        Ok((
                            format!("opt_{opt}"),
                            serde_json::Value::from(sum(
                                c,
                                &["async.recv.pending", "async.rx_irq", "async.recv.ready"],
                            )?),
                        ))
                    })
                    .collect::<Result<serde_json::Map<_, _>>>()?,
            ),
        );
        m.insert("flash_bytes_async_s".into(), size_s.async_fw.flash().into());
        m.extend(fig.summary_fields()?);
        Ok(Some(serde_json::Value::Object(m)))
    }

    /// The markdown document.
    pub fn render(&self) -> Result<String> {
        let mut s = String::new();
        let date = cmd::first_line("date", &["-u", "+%Y-%m-%d %H:%M UTC"])
            .unwrap_or_else(|| "unknown date".into());
        let _ = writeln!(s, "# Benchmarks\n");
        let _ = writeln!(
            s,
            "Generated by `cargo run --release --bin can-bench` (source: `bench/`) on {date}; \
             the run took {:.0} s after can-bench itself was built, {:.0} s of it in cargo \
             builds of firmware and of can-fil (short when they were already built). Every \
             figure in this file comes from that run — none is written by hand. Run the \
             command again to refresh it; a step that cannot run stops the command with an \
             error and leaves this file as it was.\n",
            self.elapsed_secs, self.build_secs
        );
        self.render_machine(&mut s);
        let figures = self.figures()?;
        if let Some(f) = &figures {
            render_targets(&mut s, f);
            for backend in Backend::ALL {
                render_feature_costs(&mut s, f, backend);
            }
        }
        if let Some(sizes) = &self.sizes {
            self.render_sizes(&mut s, sizes);
        }
        if let Some(ex) = &self.examples {
            render_examples(&mut s, ex);
        }
        if let Some(insn) = &self.insn {
            self.render_insn(&mut s, insn)?;
        }
        if let Some(t) = &self.timing {
            render_timing(&mut s, t);
        }
        if let Some(sim) = &self.sim {
            render_sim(&mut s, sim);
        }
        render_sources(&mut s);
        Ok(s)
    }

    fn render_sizes(&self, s: &mut String, sz: &SizeSection) {
        let _ = writeln!(s, "## 1. Flash and RAM\n");
        let _ = writeln!(
            s,
            "Read from the ELF section headers (the `object` crate). Only allocated sections \
             (`SHF_ALLOC`) count:\n\n\
             - **code**: allocated sections that are neither writable nor `NOBITS` — \
             `.vector_table`, `.text`, `.rodata` (and `.flash_config` on the Teensy): \
             flash-resident code and constants;\n\
             - **data**: writable `PROGBITS` sections (`.data`): in RAM, and their initial \
             image in flash;\n\
             - **bss**: `NOBITS` sections (`.bss`, `.uninit`): RAM only.\n\n\
             **flash = code + data**, **RAM = data + bss**, in bytes. The stack (the rest of \
             RAM) is not a section and is not counted here (section 2 measures it).\n\n\
             **Driver + application** (the issue-21 flash figure) is the flash without what \
             every firmware of a board shares and no CAN service needs: the `.vector_table` \
             and `.flash_config` sections and the code and constants of the shared start-up \
             module (the ELF symbols of the module `startup`: `shared/stm32f7.rs` — PLL, \
             flash wait states, CAN1 clock — or `shared/kinetis.rs` — watchdog, crystal \
             oscillator; its entry `clocks`/`init` is never inlined, so its code keeps its \
             symbols). The runtime's reset handler (`.bss`/`.data` set-up) and the panic \
             handler stay in.\n"
        );
        let _ = writeln!(
            s,
            "### Minimal loop-back firmware: the lean and full variants\n\n\
             Each variant is a separate build of the same firmware source, selected by the \
             cargo feature `lean` or `full` of the bench firmware crates \
             (`bench/firmware/shared/bxcan_variant.rs`, `flexcan_variant.rs` for our \
             drivers; `bxcan_equiv.rs`, `flexcan_hand.rs` for the equivalents):\n\n\
             - **full**: completions (a token per frame, a completion ring of 8), receive \
             time stamps, traffic statistics, filters from the runtime planner;\n\
             - **lean**: issue 21's lean driver — bxCAN: a `const` filter plan \
             (`const_plan!`, the planner not linked), a filter map sized to the plan (no \
             lookup key, exactly the plan's match indices) and fixed (no filter generation \
             per frame: `BxCan<R, F, 0, M, false>`), no \
             completion ring (`DONE` = 0, fire and forget), time stamps off \
             (`CAN_MCR.TTCM` = 0) and the split driver's `Lean` feature set (no traffic \
             statistics, no time stamps read), which with a request-order queue is its \
             quiet transmit mode (`State::QUIET_TX`: the transmit interrupt enabled only \
             while frames wait in the queue), registers at a compile-time base \
             (`twocan_core::Fixed`); FlexCAN: the controller's compile-time \
             `options::Lean` (no time stamps, no filter switch while running: \
             `into_split_with::<Lean>()`), the filter table planned with `const_plan!` \
             and the settings checked at compile time (`BeginPlan::new_or_panic`, written \
             by `begin_checked_in_place`: no check or planner links in), and the split \
             driver's `Lean` feature set, its quiet transmit mode there too (full: the \
             settings checked at compile time as well, the list compiled at run time by \
             `begin_in_place` into a `static` `TableSlot`, `options::FullInSlot`).\n\n\
             Every variant of both backends configures the controller in place in the \
             `static` state (`State::split_with` with `BxCan::can1_in`, \
             `FlexCan::begin_checked_in_place` or `FlexCan::begin_in_place`: no \
             controller, plan or map moves through the configuration); bxCAN's full \
             plans at run time into a `static` scratch (`twocan_core::TakeOnce`).\n\n\
             bxCAN (STM32F767ZI): the same start-up (`shared/stm32f7.rs`: SYSCLK 108 MHz \
             from the PLL, APB1 54 MHz, CAN1 clock on), CAN1 in loop-back mode at \
             500 kbit/s (the same `CAN_BTR`, solved at compile time), one accept-all filter \
             to FIFO 0, one 8-byte frame sent and received by polling, `panic-halt`:\n\n\
             - `loopback-twocan`: our split driver as an interrupt-driven application keeps \
             it — a `static State` (all zeros, `.bss`; request-order transmit), `split` \
             once, `Tx::try_send`, then the TX and RX0 handlers and `Rx::receive` polled in \
             turn until the frame comes back with its filter index (full: and its \
             completion);\n\
             - `loopback-bxcan`: the bare `bxcan` crate (`Can::builder`, `transmit`, \
             `receive`), the `Can` in a `critical_section::Mutex` static (no variant);\n\
             - `loopback-bxcan-equiv`: the `bxcan` crate plus the service that gives an \
             application what the variant of ours does (**feature-equivalent**, \
             `shared/bxcan_equiv.rs`): split once; an RX0 handler moving FIFO 0 into a \
             `heapless::spsc` ring with each frame's filter match index (read from \
             `CAN_RDT0R`, which the crate does not return), counting hardware overruns and \
             ring overflows; the thread side taking the frame with the user's filter index \
             (a table from `FMI`); full adds a token per frame, a TX handler that reads \
             `CAN_TSR` once and, in one loop over the completed mailboxes, pushes (token, \
             outcome, time stamp) into a completion ring and acknowledges them with one \
             store, the receive time stamp, counts of frames sent, failed and received.\n\n\
             FlexCAN (Teensy 3.6, MK66FX1M0): the same start-up (`shared/kinetis.rs`: \
             flash configuration field, watchdog off, 16 MHz crystal oscillator on), \
             FlexCAN0 in loop-back mode with self reception at 500 kbit/s from the \
             oscillator clock, one pass-all filter, one frame by polling:\n\n\
             - `loopback-flexcan`: our FlexCAN split driver on the 8-filter Rx FIFO \
             partition, begun in place in a `static State` (`State::split_with`; lean: \
             `begin_checked_in_place` with the compile-time plan and `options::Lean`; \
             full: `begin_in_place` compiling the list into a `static` `TableSlot`, \
             `options::FullInSlot`), as `loopback-twocan`;\n\
             - `loopback-flexcan-hand`: the hand-written register-level service of \
             `shared/flexcan_hand.rs` (there is no crate peer for Teensy 3.x): the K66 \
             manual's initialization sequence, MB15 as the transmit mailbox, an Rx FIFO \
             handler moving frames into a `heapless::spsc` ring with counts and \
             `RXFIR.IDHIT`, the thread side mapping `IDHIT` to the user's filter index \
             through a table; full adds the token, MB15's completion handler and ring, \
             the time stamps and the counts.\n\n\
             Both profiles: fat LTO, one codegen unit, `panic = \"abort\"`; the \
             size-optimised one comes first.\n"
        );
        for b in &sz.builds {
            let _ = writeln!(
                s,
                "Profile `{}` (`opt-level = {}`):\n",
                b.profile,
                if b.opt == "s" {
                    "\"s\"".to_string()
                } else {
                    b.opt.clone()
                }
            );
            let _ = writeln!(
                s,
                "| firmware | code | data | bss | **flash** | **RAM** | **driver + application** |\n\
                 |---|---:|---:|---:|---:|---:|---:|"
            );
            let row = |s: &mut String, name: &str, z: &Size| {
                let _ = writeln!(
                    s,
                    "| {name} | {} | {} | {} | **{}** | **{}** | **{}** |",
                    thousands(z.code()),
                    thousands(z.data()),
                    thousands(z.bss()),
                    thousands(z.flash()),
                    thousands(z.ram()),
                    thousands(z.app_flash())
                );
            };
            for v in &b.variants {
                row(s, &format!("`loopback-twocan` ({})", v.variant), &v.ours);
                row(
                    s,
                    &format!("`loopback-bxcan-equiv` ({})", v.variant),
                    &v.equiv,
                );
            }
            row(s, "`loopback-bxcan` (bare crate)", &b.bare);
            for v in &b.variants {
                row(
                    s,
                    &format!("`loopback-flexcan` ({})", v.variant),
                    &v.flexcan,
                );
                row(
                    s,
                    &format!("`loopback-flexcan-hand` ({})", v.variant),
                    &v.flexcan_hand,
                );
            }
            let _ = writeln!(s);
            let mut ratios = Vec::new();
            for v in &b.variants {
                ratios.push(format!(
                    "{}: bxCAN {} (whole flash {}), FlexCAN {} (whole flash {})",
                    v.variant,
                    ratio(v.ours.app_flash(), v.equiv.app_flash()),
                    ratio(v.ours.flash(), v.equiv.flash()),
                    ratio(v.flexcan.app_flash(), v.flexcan_hand.app_flash()),
                    ratio(v.flexcan.flash(), v.flexcan_hand.flash())
                ));
            }
            let _ = writeln!(
                s,
                "Driver + application, ours / the equivalent — {}. Whole flash of the full \
                 `loopback-twocan` / the bare crate: {}.\n",
                ratios.join("; "),
                b.variant("full")
                    .map(|v| ratio(v.ours.flash(), b.bare.flash()))
                    .unwrap_or_else(|| "–".into())
            );
            let _ = writeln!(s, "Sections and start-up bytes left out:\n");
            let mut list = |name: &str, z: &Size| {
                let _ = writeln!(
                    s,
                    "- `{name}`: {}; start-up module {} B",
                    z.section_list(),
                    z.startup
                );
            };
            for v in &b.variants {
                list(&format!("loopback-twocan-{}", v.variant), &v.ours);
                list(&format!("loopback-bxcan-equiv-{}", v.variant), &v.equiv);
            }
            list("loopback-bxcan", &b.bare);
            for v in &b.variants {
                list(&format!("loopback-flexcan-{}", v.variant), &v.flexcan);
                list(
                    &format!("loopback-flexcan-hand-{}", v.variant),
                    &v.flexcan_hand,
                );
            }
            let _ = writeln!(s);
        }
        if sz.fil.is_empty() {
            let _ = writeln!(
                s,
                "The loop-back firmwares were not run under can-fil in this run (`--skip \
                 fil`).\n"
            );
        } else {
            let _ = writeln!(
                s,
                "**Each loop-back firmware works**: every one runs under `can-fil --stack` \
                 (the firmware-in-the-loop harness, `fil/`: the STM32 ones on the \
                 NUCLEO-F767ZI profile, the Teensy ones on the Teensy 3.6 profile, CAN on \
                 the project's models) for {} s of simulated time, and can-bench requires \
                 that it ends without a fault or a halt and not in its panic handler (each \
                 panics unless the frame came back with its filter index and, with \
                 completions, its completion). Its stack over the run (start-up, \
                 configuration, one frame by polling), painted as for the examples:\n",
                crate::stack::SECONDS
            );
            let mut opts: Vec<&str> = Vec::new();
            let mut elfs: Vec<&str> = Vec::new();
            for r in &sz.fil {
                if !opts.contains(&r.opt.as_str()) {
                    opts.push(&r.opt);
                }
                if !elfs.contains(&r.elf.as_str()) {
                    elfs.push(&r.elf);
                }
            }
            let mut header = String::from("| firmware | board |");
            let mut rule = String::from("|---|---|");
            for o in &opts {
                let _ = write!(header, " stack, opt {o} |");
                rule.push_str("---:|");
            }
            let _ = writeln!(s, "{header}\n{rule}");
            for e in elfs {
                let board = sz
                    .fil
                    .iter()
                    .find(|r| r.elf == e)
                    .map(|r| r.board.as_str())
                    .unwrap_or("");
                let mut line = format!("| `{e}` | {board} |");
                for o in &opts {
                    match sz.fil.iter().find(|r| r.elf == e && r.opt == *o) {
                        Some(r) => {
                            let _ = write!(line, " {} |", thousands(r.stack.whole));
                        }
                        None => line.push_str(" – |"),
                    }
                }
                let _ = writeln!(s, "{line}");
            }
            let _ = writeln!(s);
        }
        let _ = writeln!(
            s,
            "**RAM of our drivers**: the `State` static (symbol size of `BENCH_CAN_STATE` \
             in the loop-back firmware), its ring and queue slots (receive ring 8 raw \
             frames, transmit queue 8 entries, completion ring `DONE` entries, state-change \
             ring 8) and the **driver state** beyond them, broken down by \
             `twocan_core::split::Footprint` (`State::FOOTPRINT`, `size_of` of each part on \
             the target; the instruction-count firmware of the same variant holds a `State` \
             of the same type and exports it as `BENCH_FOOTPRINT`, its total checked equal \
             to the static's size). The controller value includes its publication stage \
             and lease count (8 B); inside it, the filter map (bxCAN) or the filter table \
             handle (FlexCAN: a planned table's slices, or a reference to a `static` slot) \
             and FlexCAN's clock-gate and pin plan kept for `end`. A ring of capacity 0 \
             (the second receive queue, `RX1` = 0; the completion ring with `DONE` = 0) \
             still keeps its indices (16 B each). The halves and handlers (`split`'s \
             `Parts`) live wherever the application keeps them.\n"
        );
        let _ = writeln!(
            s,
            "| backend | variant | `State` | slots | **driver state** | controller | of which filters | of which pin plan | ring bookkeeping | queue bookkeeping | time-stamp clock | statistics | rare-event counts | wakers | padding |\n\
             |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
        );
        let mut rows: Vec<(Backend, &str, &StateFigures)> = Vec::new();
        for st in &sz.states {
            for b in Backend::ALL {
                rows.push((b, &st.variant, st.of(b)));
            }
        }
        for b in Backend::ALL {
            for (fb, v, st) in &sz.feature_states {
                if *fb == b {
                    rows.push((b, v, st));
                }
            }
        }
        for (b, variant, f) in rows {
            let opt = |v: Option<u64>| v.map(thousands).unwrap_or_else(|| "–".into());
            let fp = &f.footprint;
            let _ = writeln!(
                s,
                "| {} | {variant} | {} | {} | **{}** | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                b.name(),
                thousands(f.static_bytes),
                thousands(f.ring_bytes),
                thousands(f.state_bytes()),
                thousands(fp.controller),
                opt(f.fmi_bytes),
                opt(f.system_bytes),
                fp.ring_bookkeeping,
                fp.queue_bookkeeping,
                fp.clock,
                fp.statistics,
                fp.errors,
                fp.wakers,
                fp.padding
            );
        }
        let _ = writeln!(s);
    }

    fn render_insn(&self, s: &mut String, insn: &InsnSection) -> Result<()> {
        let _ = writeln!(
            s,
            "## 2. Instructions per frame and stack on a Cortex-M4 (QEMU)\n"
        );
        let _ = writeln!(
            s,
            "Guest instructions executed, counted by the TCG plugin \
             `bench/plugin/insn_count.c` (built at bench time with `gcc {}`) while QEMU \
             runs the firmwares `bench/firmware/insn-count` (bxCAN: ours and the bare \
             `bxcan` crate), `bench/firmware/insn-count-equiv` (the feature-equivalent \
             service, in an image of its own so that the crate's `transmit` is not shared \
             with the bare measurement and stays inlined, as in a firmware using it alone; \
             its figures are merged with `insn-count`'s) and \
             `bench/firmware/insn-count-flexcan` (FlexCAN: ours, the hand-written service), \
             each built as the lean and as the full variant (section 1), on `-machine {}` (an ARM MPS2 board with a \
             Cortex-M4). This is an instruction count, not a cycle count: QEMU does not \
             model pipeline, wait states or bus timing.\n",
            qemu::PLUGIN_FLAGS.join(" "),
            qemu::MACHINE
        );
        let _ = writeln!(
            s,
            "No Debian 12 package ships QEMU's plugin header `qemu-plugin.h` (checked \
             when the bench was written: `apt-file search qemu-plugin.h` on bookworm finds \
             nothing, and the qemu-system packages list no header; in this run, {}), so the \
             plugin declares the few plugin API types and functions it uses itself, from \
             the documented plugin API (`qemu_plugin_install`, `qemu_plugin_version` = 1, \
             the translation callback, per-instruction execution callbacks, memory \
             callbacks on stores, `qemu_plugin_register_atexit_cb`, `qemu_plugin_outs`). \
             It copies nothing from QEMU's header.\n",
            insn.tools.header_search
        );
        let _ = writeln!(
            s,
            "**Register stand-ins.** QEMU's board has neither bxCAN nor FlexCAN, so RAM \
             blocks outside every linker section stand in for the registers: CAN1's at \
             `0x2010_0000` (`shared/ram_can.rs`; our driver through \
             `twocan_core::Mmio::new`, the `bxcan` crate through its \
             `Instance::REGISTERS`), FlexCAN0's at `0x2010_8000` \
             (`shared/ram_flexcan.rs`). Every driver is configured through its public API \
             while a SysTick handler plays the mode handshakes (bxCAN `INRQ` → `INAK`, \
             `SLEEP` → `SLAK`; FlexCAN `MDIS` → `LPMACK`, `FRZ`+`HALT` → `FRZACK` and \
             `NOTRDY`, `SOFTRST` clearing itself); SysTick is off before anything is \
             measured. RAM does not react like the peripheral, so **each measured call does \
             exactly one frame's work from a freshly restored snapshot** of the register \
             block, showing what the controller would show, and the firmware checks the \
             effect afterwards (frame in the mailbox, frame in the ring, FIFO released, \
             completion taken with its token, filter index); a failed check fails the run. \
             bxCAN snapshots: all mailboxes empty; mailbox 0 pending with a lower-priority \
             frame; all three pending with higher-priority frames (our driver queues); \
             mailbox 0 empty with its completion already acknowledged (refill); mailbox 0 \
             completed (`RQCP0`, `TXOK0`); FIFO 0 with one frame (`FMP0` = 1; a release \
             store leaves `FMP0` = 0, as after the last frame). FlexCAN snapshots: MB15 \
             inactive; MB15 sent (its `IFLAG1` bit set); the Rx FIFO with one frame \
             (`BUF5I`). FlexCAN's write-1-to-clear flags (`IFLAG1`, `ESR1`) would stay set \
             on RAM and a receive loop popping the FIFO until `BUF5I` reads 0 would not \
             end, so **both FlexCAN drivers** reach the block through an accessor that \
             plays the rule (a write of `v` stores `old & !v`): one extra load and `BIC` \
             per such write, on both sides alike, that hardware would not execute.\n"
        );
        let _ = writeln!(
            s,
            "**Counting.** A measurement counts the instructions executed after a start \
             marker (a store to the plugin's marker window at `{:#010x}`, outside every \
             linker section) up to and including the end marker store; each measured \
             function is `#[inline(never)]` and gets its arguments through \
             `core::hint::black_box`, so a figure includes its call and return. The \
             instructions of an empty region (start marker directly followed by the end \
             marker) are subtracted. Each region is measured {} times per build; a figure \
             is the smallest (the steady state: the first measurement may also raise a \
             ring's peak figure). The frame is a standard data frame, identifier 0x123, \
             8 bytes. **Round trips** are summed from the regions the firmware names for \
             its configuration (the `roundtrip` lines it prints): the send, every handler \
             the configuration runs per frame (our transmit handler runs in the full \
             variants, which enable the transmit interrupt; the lean variants are the \
             quiet transmit mode, whose transmit interrupt is off while nothing is queued \
             — the firmware checks `CAN_IER.TMEIE` on bxCAN, MB15's `IMASK1` bit on \
             FlexCAN, after each direct send — so a frame sent directly runs no handler; the lean \
             equivalents have none — fire-and-forget needs none), the take, and with completions the \
             completion's take. On FlexCAN one interrupt line runs both handlers; each is \
             measured on its own, on both sides.\n",
            insn.window,
            insn.runs.first().map(|r| r.counts.repeats()).unwrap_or(0)
        );
        let _ = writeln!(
            s,
            "**Stack.** After the counts each measured call runs once more for its stack \
             high-water mark, by painting (`shared/qemu.rs`): {} bytes below the stack \
             pointer are filled with a pattern by one inline-assembly loop that pushes \
             nothing, the call runs, and the deepest word that lost the pattern gives the \
             bytes the call used below its caller's stack pointer (its frame and its \
             callees'; an interrupt handler on hardware adds the 32-byte exception frame, \
             104 with FP context). The **configuration** figure is the same for the whole \
             configuration of a driver, from the register handle to the handles of the \
             split (ours: the controller configured in place in the `State` by \
             `State::split_with` — bxCAN `BxCan::can1_in`, FlexCAN \
             `begin_checked_in_place` or `begin_in_place` — with the filters and the \
             split; the equivalents: the crate's builder or the hand-written \
             initialization, the split). During it the handshake stand-in's SysTick \
             interrupts push their 8-word frames on the measured stack (FP context \
             stacking is turned off meanwhile, and the handler is assembly that pushes \
             nothing else and records where each frame went): the figure given counts \
             them (an upper bound), the table notes the lower bound where a frame was the \
             deepest word.\n",
            thousands(
                insn.runs
                    .first()
                    .and_then(|r| r.counts.notes.get("stack.painted_bytes").copied())
                    .unwrap_or(0)
            )
        );
        render_breakdown(s, insn)?;
        let _ = writeln!(s, "### Every measured region\n");
        for backend in Backend::ALL {
            let mut cols = Vec::new();
            for variant in VARIANTS {
                for opt in insn.opts() {
                    if let Ok(c) = insn.get(backend, variant, &opt) {
                        cols.push((variant, opt.clone(), c));
                    }
                }
            }
            if cols.is_empty() {
                continue;
            }
            let _ = writeln!(s, "{} (`{}`):\n", backend.name(), backend.firmware());
            let mut header = String::from("| region | what is measured |");
            let mut rule = String::from("|---|---|");
            for (v, opt, _) in &cols {
                let _ = write!(header, " {v}, opt {opt} |");
                rule.push_str("---:|");
            }
            let _ = writeln!(s, "{header}\n{rule}");
            let mut keys: Vec<&String> = Vec::new();
            for (_, _, c) in &cols {
                for k in c.regions.keys() {
                    if k != "empty" && !keys.contains(&k) {
                        keys.push(k);
                    }
                }
            }
            keys.sort_by_key(|k| region_order(k));
            for k in keys {
                let mut line = format!("| `{k}` | {} |", region_note(k));
                for (_, _, c) in &cols {
                    match c.net(k) {
                        Ok((lo, hi)) if lo == hi => {
                            let _ = write!(line, " {} |", thousands(lo));
                        }
                        Ok((lo, hi)) => {
                            let _ = write!(line, " {} ({lo}–{hi}) |", thousands(lo));
                        }
                        Err(_) => line.push_str(" – |"),
                    }
                }
                let _ = writeln!(s, "{line}");
            }
            let mut line =
                String::from("| **round trip, ours** | the regions of `roundtrip twocan` |");
            for (_, _, c) in &cols {
                let _ = write!(line, " **{}** |", thousands(c.roundtrip("twocan")?));
            }
            let _ = writeln!(s, "{line}");
            let mut line = format!(
                "| **round trip, {}** | the regions of `roundtrip {}` |",
                backend.equivalent(),
                backend.equivalent()
            );
            for (_, _, c) in &cols {
                let _ = write!(
                    line,
                    " **{}** |",
                    thousands(c.roundtrip(backend.equivalent())?)
                );
            }
            let _ = writeln!(s, "{line}\n");
            let overheads: Vec<String> = cols
                .iter()
                .map(|(v, opt, c)| format!("{} ({v}, opt {opt})", c.overhead))
                .collect();
            let _ = writeln!(
                s,
                "Marker overhead subtracted: {}. Where a region's measurements differed \
                 the range is given.\n",
                overheads.join(", ")
            );

            let _ = writeln!(s, "Stack high-water marks, bytes ({}):\n", backend.name());
            let _ = writeln!(s, "{header}\n{rule}");
            let mut skeys: Vec<&String> = Vec::new();
            for (_, _, c) in &cols {
                for k in c.stacks.keys() {
                    if !skeys.contains(&k) {
                        skeys.push(k);
                    }
                }
            }
            skeys.sort_by_key(|k| (!k.ends_with(".config"), region_order(k)));
            for k in skeys {
                let what = if k.ends_with(".config") {
                    "configuration (whole, see above)"
                } else {
                    region_note(k)
                };
                let mut line = format!("| `{k}` | {what} |");
                for (_, _, c) in &cols {
                    match (c.stacks.get(k), c.notes.get(&format!("{k}.low"))) {
                        (Some(v), Some(low)) if low != v => {
                            let _ = write!(line, " {} (≥ {}) |", thousands(*v), thousands(*low));
                        }
                        (Some(v), _) => {
                            let _ = write!(line, " {} |", thousands(*v));
                        }
                        (None, _) => line.push_str(" – |"),
                    }
                }
                let _ = writeln!(s, "{line}");
            }
            let _ = writeln!(s);
        }
        self.render_async(s, insn)?;
        let _ = writeln!(s, "QEMU command line (per build):\n");
        let example = qemu::command(
            &insn.tools,
            std::path::Path::new(
                "target/bench-firmware/thumbv7em-none-eabihf/release/insn-count-lean",
            ),
            std::path::Path::new("target/bench-plugin/insn_count.so"),
            insn.window,
            std::path::Path::new("target/bench-plugin/counts-release-bxcan-lean.txt"),
        );
        let line = cmd::display(&example)
            .replace(&insn.tools.qemu.display().to_string(), "qemu-system-arm");
        let _ = writeln!(s, "```\n{line}\n```\n");
        Ok(())
    }

    fn render_machine(&self, s: &mut String) {
        let _ = writeln!(s, "## Machine and tools\n");
        let _ = writeln!(s, "| | |\n|---|---|");
        for (k, v) in machine() {
            let _ = writeln!(s, "| {k} | {v} |");
        }
        if let Some(i) = &self.insn {
            let installed = if i.tools.qemu_installed_now {
                " (installed by this run: `apt-get install -y qemu-system-arm`)"
            } else {
                ""
            };
            let _ = writeln!(s, "| QEMU | {}{installed} |", i.tools.qemu_version);
            let _ = writeln!(s, "| gcc (plugin) | {} |", i.tools.gcc_version);
        }
        let lock = self.paths.firmware().join("Cargo.lock");
        for krate in [
            "bxcan",
            "heapless",
            "cortex-m",
            "cortex-m-rt",
            "cortex-m-semihosting",
        ] {
            if let Some(v) = firmware::locked_version(&lock, krate) {
                let _ = writeln!(s, "| `{krate}` crate (bench firmware) | {v} |");
            }
        }
        let _ = writeln!(s, "| firmware target | `{TARGET}` |\n");
    }
}

/// The targets of issue 21 with their verdicts (first in the document: the headline).
fn render_targets(s: &mut String, f: &Figures) {
    let _ = writeln!(s, "## Targets of issue 21 (zero-cost by construction)\n");
    let _ = writeln!(
        s,
        "Each line: ours / theirs, per opt-level (instructions from section 2, flash from \
         section 1, stack from section 2), against the issue's bound; \"met\" or by how \
         much it is missed. **Lean** is issue 21's lean driver configuration (section 1 \
         says what each backend's lean build uses). **Full** has completions, time \
         stamps, statistics and the runtime planner. The equivalents do the same service \
         in each variant (section 1). Byte bounds: driver state ≤ the rings + \
         {} B; configuration stack ≤ {} B.\n",
        figures::STATE_BOUND,
        figures::CONFIG_STACK_BOUND
    );
    let opts: Vec<String> = {
        let mut v: Vec<String> = Vec::new();
        for t in &f.targets {
            for (o, _) in &t.per_opt {
                if !v.contains(o) {
                    v.push(o.clone());
                }
            }
        }
        v
    };
    let mut header = String::from("| backend | variant | target |");
    let mut rule = String::from("|---|---|---|");
    for o in &opts {
        let _ = write!(header, " opt {o} |");
        rule.push_str("---:|");
    }
    header.push_str(" bound | verdict |");
    rule.push_str("---:|---|");
    let _ = writeln!(s, "{header}\n{rule}");
    let mut missed = Vec::new();
    for t in &f.targets {
        let mut line = format!("| {} | {} | {} |", t.backend.name(), t.variant, t.label);
        let mut verdicts = Vec::new();
        for o in &opts {
            match t.at(o) {
                Some(m @ Measured::Ratio { ours, theirs }) => {
                    let _ = write!(
                        line,
                        " {} / {} = **{:.2}** |",
                        thousands(*ours),
                        thousands(*theirs),
                        m.value()
                    );
                }
                Some(Measured::Bytes(b)) => {
                    let _ = write!(line, " **{}** B |", thousands(*b));
                }
                None => line.push_str(" – |"),
            }
            if let (Some(m), Some(bound)) = (t.at(o), t.bound) {
                let v = m.verdict(bound);
                if v != "met" {
                    missed.push(format!(
                        "{} {} {} (opt {o})",
                        t.backend.name(),
                        t.variant,
                        t.key
                    ));
                }
                verdicts.push(format!("opt {o}: {v}"));
            }
        }
        let bound = match (t.bound, t.key) {
            (None, _) => "–".to_string(),
            (Some(b), "state" | "config_stack") => format!("≤ {} B", thousands(b as u64)),
            (Some(b), _) => format!("≤ {b:.1}"),
        };
        let verdict = if verdicts.is_empty() {
            "(extra line)".to_string()
        } else {
            verdicts.join("; ")
        };
        let _ = writeln!(s, "{line} {bound} | {verdict} |");
    }
    let _ = writeln!(s);
    if let Some((v, what)) = &f.config_stack_max {
        let _ = writeln!(
            s,
            "**Largest configuration stack** (`config_stack_bytes_max`) of every firmware \
             example (can-fil, up to the last CAN controller started having a line \
             unmasked, the second controller of the two-controller examples included; \
             section 1), \
             every loop-back bench firmware (can-fil, whole run; section 1) and every \
             instruction-count bench firmware (QEMU, the configuration call; section 2 and, \
             for the one-feature variants, the next section): \
             **{} B**, {what} ({}).\n",
            thousands(*v),
            Measured::Bytes(*v).verdict(figures::CONFIG_STACK_BOUND as f64)
        );
    }
    let bounded = f
        .targets
        .iter()
        .filter(|t| t.bound.is_some())
        .map(|t| t.per_opt.len())
        .sum::<usize>();
    if !missed.is_empty() {
        let _ = writeln!(
            s,
            "{} of the {bounded} bounded figures miss their bound. Each missed target \
             below: what the extra work is, then where it goes, measured in this run (a \
             round trip step by step, ours / theirs; flash by the crate defining the code, \
             from the ELF's function symbols, code inlined into another crate's function \
             counting there; the driver state by `State::FOOTPRINT`).\n",
            missed.len()
        );
        for t in &f.targets {
            let Some(bound) = t.bound else { continue };
            let verdicts: Vec<String> = t
                .per_opt
                .iter()
                .filter_map(|(o, m)| {
                    let v = m.verdict(bound);
                    (v != "met").then(|| format!("opt {o} {v}"))
                })
                .collect();
            if verdicts.is_empty() {
                continue;
            }
            let _ = writeln!(
                s,
                "- **{} {} {}** ({}): {} Measured: {}.",
                t.backend.name(),
                t.variant,
                t.key,
                verdicts.join(", "),
                why_missed(t.backend, t.variant, t.key),
                if t.cause.is_empty() {
                    "see section 2".to_string()
                } else {
                    t.cause.join("; ")
                }
            );
        }
        let _ = writeln!(s);
    }
}

/// What the extra work behind a missed target is (the mechanism; the measured split
/// follows it in the document).
fn why_missed(backend: Backend, variant: &str, key: &str) -> &'static str {
    match (backend, variant, key) {
        (Backend::BxCan, _, "tx") => {
            "the send does what the portable API promises: it checks bus-off and \
             listen-only, loads a mailbox directly only with an empty queue (so that \
             order is kept), keeps the token and load order per mailbox (for `abort` and \
             `mailbox_state`), and encodes the portable `Frame` into the mailbox \
             registers, where the `bxcan` crate's frame is kept in register form."
        }
        (Backend::FlexCan, _, "tx") => {
            "the send checks bus-off and listen-only, loads the data mailbox directly \
             only with an empty queue, keeps the token and load order, follows the \
             manual's transmit process (mailbox code written INACTIVE first, the flag \
             cleared, then the words and the code) and encodes the portable `Frame`; the \
             hand-written send writes a mailbox it knows is free."
        }
        (Backend::BxCan, _, "rx_isr") => {
            "the handler drains FIFO 0 in a loop, as the equivalent does: per pass one \
             read of `CAN_RF0R` gives the pending count and the overrun and full flags \
             (one branch to the out-of-line event count, see the overrun line above), \
             the frame's four words go into the ring, and the ring keeps its peak (a \
             load, a compare, a store) that the buffer statistics report; the \
             equivalent's `heapless` queue keeps no peak."
        }
        (Backend::FlexCan, _, "rx_isr") => {
            "the handler drains the Rx FIFO in a loop, as the hand-written one does: per \
             pass it also loads the controller's mode word (no FIFO read while the \
             module is disabled for sleep) and reaches the controller through the \
             state's published slot, and the ring push keeps its peak (a load, a compare, \
             a store) that the buffer statistics report; the hand-written ring keeps \
             none."
        }
        (_, "lean", "roundtrip") => {
            "the send's checks and encoding (above) and, on the thread side, the take \
             decodes the raw words into the portable `Frame` (identifier, DLC, data \
             beyond the length cleared) and maps the hardware's filter hit to the user's \
             filter index through the filter map; the equivalents hand over their \
             frame type and the raw filter index."
        }
        (_, _, "roundtrip") => {
            "besides the lean round trip's work, every frame runs the transmit handler \
             (a completion per frame into the ring, with its token and time stamp), the \
             time stamps are widened in a critical section and the statistics counted; \
             the equivalents record a completion with fewer checks."
        }
        (Backend::BxCan, "lean", "flash") => {
            "the split driver links the transmit path for a busy mailbox and queued \
             frames (`service_tx`, `send_queued`), which the loop-back never takes but an \
             application may, the error-state read its status handler and `split` use \
             (`error_status`), and a configuration (mode requests with their time-outs, \
             the filter block's programming) inlined into `main`; `compiler_builtins` \
             adds the `memclr` that zeroes words of the controller written in place \
             (the largest functions below)."
        }
        (Backend::FlexCan, "lean", "flash") => {
            "as bxCAN's (`service_tx` is larger: the remote-frame mailboxes are served \
             there too), and `compiler_builtins` links `memclr` (twice at opt s) for the \
             controller's zeroed words when it is written in place (the largest \
             functions below)."
        }
        (_, _, "flash") => {
            "the full variant links the run-time filter planner and table compiler, \
             which the equivalent does not have (it writes one fixed filter)."
        }
        (Backend::BxCan, _, "state") => {
            "the state is the portable driver's own bookkeeping: the controller value \
             (the filter map, the token and load order per mailbox, mode and handshake \
             bounds, error-state memory), the indices, peaks and overflow counts of four \
             rings (also of the rings of capacity 0: a ring's bookkeeping does not \
             depend on its capacity in stable Rust's types), the queue's, and the \
             rare-event counts kept in every feature set."
        }
        (Backend::FlexCan, _, "state") => {
            "as bxCAN's, and the controller also keeps the chip-level plan `end` undoes \
             (its layout's own, `Layout::System`: the Kinetis `PortPlan`, 32 B; the \
             RT1062's `ImxrtPlan` with its pads) and the planned table's slices (48 B: a \
             reference to a `static` slot, as `lean+planner` keeps, is 44 B less)."
        }
        _ => "see section 2.",
    }
}

/// A signed difference: `+12`, `−3`, `±0`.
pub fn signed(d: i64) -> String {
    match d.cmp(&0) {
        std::cmp::Ordering::Greater => format!("+{}", thousands(d.unsigned_abs())),
        std::cmp::Ordering::Less => format!("−{}", thousands(d.unsigned_abs())),
        std::cmp::Ordering::Equal => "±0".into(),
    }
}

/// `ours` against `lean`, signed.
fn delta(ours: u64, lean: u64) -> String {
    signed(ours as i64 - lean as i64)
}

/// What a one-feature variant of `backend`'s driver switches on and what its per-frame
/// code then does (the mechanism; the measured figures follow it in the document).
fn feature_note(backend: Backend, feature: &str) -> &'static str {
    match (backend, feature) {
        (_, "done") => {
            "transmit completions, a completion ring of 8 (`DONE` = 8): the send records \
             the frame's token with its mailbox; with a completion to report the split \
             driver leaves its quiet transmit mode, so the transmit interrupt stays \
             enabled and every frame runs the transmit handler, which settles the \
             mailbox into the ring, and the application takes the completion"
        }
        (Backend::BxCan, "stamps") => {
            "receive time stamps (`CAN_MCR.TTCM` = 1, a feature set with `TIMESTAMPS` \
             and without counts): the receive path keeps the frame's time stamp and the \
             take widens it; a time stamp to record per frame sent ends the quiet \
             transmit mode (`State::QUIET_TX` needs neither time stamps nor counts), so \
             every frame also runs the transmit handler"
        }
        (Backend::FlexCan, "stamps") => {
            "receive and transmit time stamps (controller options with `STAMPS`: the \
             message buffer's 16-bit `TIME STAMP` read with the frame, and a feature set \
             with `TIMESTAMPS` and without counts): the take widens it; a time stamp to \
             record per frame sent ends the quiet transmit mode, so every frame also \
             runs the transmit handler"
        }
        (_, "counts") => {
            "traffic statistics (a feature set with `COUNTS` and twocan-core's \
             counting `Counter`, no time stamps): the handlers count the frames \
             received and sent; a count to record per frame sent ends the quiet \
             transmit mode, so every frame also runs the transmit handler"
        }
        (Backend::BxCan, "switch") => {
            "filters replaceable while running (`SWITCH` = true, the filter map sized \
             as lean): each frame carries the filter list generation, read with it \
             into the ring by the receive handler and compared with the current one \
             by the take"
        }
        (Backend::FlexCan, "switch") => {
            "filter lists replaceable while running (controller options with \
             `FILTER_SWITCH`, the table still the `const` plan): each raw frame carries \
             the filter list generation, read with it into the ring by the receive \
             handler and compared with the current one by the take"
        }
        (Backend::BxCan, "planner") => {
            "the run-time planner (`planner::plan_in`, its working memory in a \
             `static`) instead of the `const` plan, the map sized to the same plan: its \
             cost is the planner's code in flash, its working memory in RAM and the \
             planning on the configuration's stack; the per-frame code is lean's"
        }
        (Backend::FlexCan, "planner") => {
            "the filter list compiled at run time by `FlexCan::begin_in_place` \
             straight into a `static` `TableSlot` (controller options with a reference \
             to it) instead of the `const` plan (the settings still checked at compile \
             time): its cost is the table compiler and the table in flash and RAM and \
             the compilation on the configuration's stack; the per-frame code reads the \
             owned table where lean reads the plan"
        }
        _ => "",
    }
}

/// Issue 21's "each choice with its own measured cost": every one-feature variant of
/// `backend`'s driver against lean.
fn render_feature_costs(s: &mut String, f: &Figures, backend: Backend) {
    let costs: Vec<&FeatureCost> = f.feature_costs_of(backend).collect();
    let Some(first) = costs.first() else {
        return;
    };
    let (insn, loopback) = (backend.firmware(), backend.loopback());
    let shared = match backend {
        Backend::BxCan => "bxcan_variant.rs",
        Backend::FlexCan => "flexcan_variant.rs",
    };
    let _ = writeln!(
        s,
        "## What each per-frame choice costs ({})\n",
        backend.name()
    );
    let _ = writeln!(
        s,
        "Each compile-time choice measured on its own: a **one-feature variant** is the \
         lean variant of our {name} driver with exactly one choice switched to its full \
         setting (cargo feature `lean` plus one of `done`, `stamps`, `counts`, `switch`, \
         `planner` of `bench/firmware/{insn}` and `{loopback}`; \
         `shared/{shared}`), built with both profiles and measured as lean is: \
         the round trip from `{insn}` under QEMU (the regions the firmware names \
         for its configuration, section 2; a choice that ends the quiet transmit mode \
         adds the transmit handler), flash and RAM from `{loopback}` (section 1), \
         the `State` static (`BENCH_CAN_STATE`, and the driver state beyond its ring \
         and queue slots) and the configuration stack from `{insn}`. Every Δ is \
         against lean at the same opt-level; \"steps that changed\" lists each round-trip \
         region whose count differs from lean's (\"new\": lean's round trip does not \
         run it).\n",
        name = backend.name()
    );
    let _ = writeln!(
        s,
        "| variant | opt | round trip | Δ | steps that changed (Δ) | driver + application flash | Δ | RAM | Δ | `State` / driver state, B | Δ | configuration stack, B | Δ |\n\
         |---|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    let opts: Vec<String> = first.per_opt.iter().map(|o| o.opt.clone()).collect();
    let lean_state = first.state.1;
    for opt in &opts {
        if let Some(o) = first.at(opt) {
            let _ = writeln!(
                s,
                "| lean | {opt} | **{}** | | | **{}** | | {} | | {} / **{}** | | {} | |",
                thousands(o.roundtrip.1),
                thousands(o.flash.1),
                thousands(o.ram.1),
                thousands(lean_state.static_bytes),
                thousands(lean_state.state_bytes()),
                thousands(o.config_stack.1)
            );
        }
    }
    for c in &costs {
        let (st, lean) = c.state;
        for o in &c.per_opt {
            let steps = if o.steps.is_empty() {
                "none".to_string()
            } else {
                o.steps
                    .iter()
                    .map(|st| {
                        let d = signed(st.delta());
                        match (st.ours, st.lean) {
                            (Some(_), None) => format!("`{}` {d} (new)", st.key),
                            (None, Some(_)) => format!("`{}` {d} (not run)", st.key),
                            _ => format!("`{}` {d}", st.key),
                        }
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let _ = writeln!(
                s,
                "| {} | {} | **{}** | {} | {steps} | **{}** | {} | {} | {} | {} / **{}** | {} / {} | {} | {} |",
                c.variant,
                o.opt,
                thousands(o.roundtrip.0),
                delta(o.roundtrip.0, o.roundtrip.1),
                thousands(o.flash.0),
                delta(o.flash.0, o.flash.1),
                thousands(o.ram.0),
                delta(o.ram.0, o.ram.1),
                thousands(st.static_bytes),
                thousands(st.state_bytes()),
                delta(st.static_bytes, lean.static_bytes),
                delta(st.state_bytes(), lean.state_bytes()),
                thousands(o.config_stack.0),
                delta(o.config_stack.0, o.config_stack.1)
            );
        }
    }
    let _ = writeln!(s);
    for c in &costs {
        let figures: Vec<String> = c
            .per_opt
            .iter()
            .map(|o| {
                format!(
                    "round trip {} instructions at opt {}",
                    delta(o.roundtrip.0, o.roundtrip.1),
                    o.opt
                )
            })
            .chain(c.per_opt.first().map(|o| {
                format!(
                    "flash {} B and RAM {} B at opt {}",
                    delta(o.flash.0, o.flash.1),
                    delta(o.ram.0, o.ram.1),
                    o.opt
                )
            }))
            .chain([format!(
                "`State` {} B",
                delta(c.state.0.static_bytes, c.state.1.static_bytes)
            )])
            .collect();
        let _ = writeln!(
            s,
            "- **{}** — {}: {}.",
            c.variant,
            feature_note(backend, c.feature),
            figures.join(", ")
        );
    }
    let _ = writeln!(s);
}

/// The round trips step by step, ours next to the equivalent's.
fn render_breakdown(s: &mut String, insn: &InsnSection) -> Result<()> {
    let _ = writeln!(
        s,
        "### Round trip by step
"
    );
    for backend in Backend::ALL {
        for variant in VARIANTS {
            let runs: Vec<(String, &Counts)> = insn
                .opts()
                .into_iter()
                .filter_map(|o| insn.get(backend, variant, &o).ok().map(|c| (o, c)))
                .collect();
            let Some((_, first)) = runs.first() else {
                continue;
            };
            let eq = backend.equivalent();
            let ours = first.roundtrip_keys("twocan")?;
            let theirs = first.roundtrip_keys(eq)?;
            let _ = writeln!(s, "{} {variant}:\n", backend.name());
            let mut header = String::from("| step | ours | theirs |");
            let mut rule = String::from("|---|---|---|");
            for (o, _) in &runs {
                let _ = write!(header, " ours, opt {o} | theirs, opt {o} |");
                rule.push_str("---:|---:|");
            }
            let _ = writeln!(s, "{header}\n{rule}");
            let mut steps: Vec<(u8, &'static str)> =
                ours.iter().chain(theirs).map(|k| step_of(k)).collect();
            steps.sort();
            steps.dedup();
            for (n, what) in steps {
                let o = ours.iter().find(|k| step_of(k).0 == n);
                let t = theirs.iter().find(|k| step_of(k).0 == n);
                let name = |k: Option<&String>| k.map(|k| format!("`{k}`")).unwrap_or("–".into());
                let mut line = format!("| {what} | {} | {} |", name(o), name(t));
                for (_, c) in &runs {
                    let cell = |k: Option<&String>| -> Result<String> {
                        Ok(match k {
                            Some(k) => thousands(c.net(k)?.0),
                            None => "–".into(),
                        })
                    };
                    let _ = write!(line, " {} | {} |", cell(o)?, cell(t)?);
                }
                let _ = writeln!(s, "{line}");
            }
            let mut line = String::from("| **sum** | | |");
            for (_, c) in &runs {
                let _ = write!(
                    line,
                    " **{}** | **{}** |",
                    thousands(c.roundtrip("twocan")?),
                    thousands(c.roundtrip(eq)?)
                );
            }
            let _ = writeln!(s, "{line}\n");
        }
    }
    Ok(())
}

fn render_examples(s: &mut String, e: &ExampleSection) {
    let _ = writeln!(s, "### Firmware examples\n");
    if e.builds.is_empty() {
        let _ = writeln!(
            s,
            "No firmware example (a package under `examples/` with binaries and a \
             `cortex-m-rt` dependency) exists yet, so none was measured.\n"
        );
        return;
    }
    let _ = writeln!(
        s,
        "Every binary of every firmware package under `examples/` (binaries and a \
         `cortex-m-rt` dependency), for each board feature, built with `cargo build \
         --release --target {TARGET} -p PACKAGE --features BOARD --bins` (the workspace's \
         release profile).\n"
    );
    match &e.stack_skipped {
        None => {
            let _ = writeln!(
                s,
                "**Stack**: each ELF runs for {} s of simulated time under `can-fil --stack \
                 --board BOARD` (the firmware-in-the-loop harness, `fil/`, with the CAN \
                 controllers on its models; `fil/src/stack.rs`): the RAM between the end of \
                 the statics (`_stack_end`) and the initial stack pointer is painted before \
                 reset; **configuration** is the painted depth when the last CAN \
                 controller the firmware starts has its first interrupt line unmasked in \
                 the NVIC (the examples unmask a controller's lines once its driver is \
                 configured and split: start-up, the configuration of every controller — \
                 the second of the two-controller examples included, with whatever the \
                 first one's handlers pushed meanwhile — and everything `main` holds by \
                 then), **whole run** the depth at the end (thread code, \
                 handlers and their exception frames). An example alone on the bus gets no \
                 acknowledgement; that does not change its configuration.\n",
                crate::stack::SECONDS
            );
        }
        Some(why) => {
            let _ = writeln!(s, "**Stack**: not measured in this run ({why}).\n");
        }
    }
    let _ = writeln!(
        s,
        "| package | board | binary | code | data | bss | **flash** | **RAM** | stack: configuration | stack: whole run |\n\
         |---|---|---|---:|---:|---:|---:|---:|---:|---:|"
    );
    for b in &e.builds {
        let (cfg, whole) = match b.stack {
            Some(st) => (
                st.configuration
                    .map(thousands)
                    .unwrap_or_else(|| "not reached".into()),
                thousands(st.whole),
            ),
            None => ("–".into(), "–".into()),
        };
        let _ = writeln!(
            s,
            "| `{}` (`{}`) | {} | `{}` | {} | {} | {} | **{}** | **{}** | {cfg} | {whole} |",
            b.package,
            b.dir,
            b.board.as_deref().unwrap_or("(no feature)"),
            b.bin,
            thousands(b.size.code()),
            thousands(b.size.data()),
            thousands(b.size.bss()),
            thousands(b.size.flash()),
            thousands(b.size.ram())
        );
    }
    let _ = writeln!(s);
}

/// Sort key of a region: transmit, handlers, takes; ours first.
fn region_order(key: &str) -> (u8, String) {
    let side = if key.starts_with("twocan.") { 0 } else { 1 };
    (side, key.to_string())
}

/// What a region (or stack figure) measures.
fn region_note(key: &str) -> &'static str {
    match key {
        "twocan.tx.direct" => "`Tx::try_send`, mailbox free, queue empty (direct path)",
        "twocan.tx.one_busy" => "`Tx::try_send`, mailbox 0 busy (direct path into mailbox 1)",
        "twocan.tx.queued" => {
            "`Tx::try_send`, all mailboxes busy: the frame joins the queue (critical section)"
        }
        "twocan.tx_irq.refill" => "`TxIrq::on_interrupt`: queue → the mailbox freed",
        "twocan.tx_irq.done" => "`TxIrq::on_interrupt`: one completion settled, nothing queued",
        "twocan.tx_irq.done.unloaded" => {
            "`TxIrq::on_interrupt` with nothing to settle (the handler's fixed cost)"
        }
        "twocan.rx_irq" => "`RxIrq::on_interrupt`: one frame into the raw ring, FIFO released",
        "twocan.rx_irq.overrun" => {
            "`RxIrq::on_interrupt`: one frame with the FIFO's overrun flag set (the frame \
             into the ring, the overrun counted out of line)"
        }
        "twocan.rx.receive" => "`Rx::receive`: ring → decoded frame with filter index",
        "twocan.take_completion" => "`Tx::take_completion`: the frame's completion",
        "bxcan.transmit" => "`bxcan` `Can::transmit`, all mailboxes empty",
        "bxcan.transmit.one_busy" => "`bxcan` `Can::transmit`, mailbox 0 busy (lower priority)",
        "bxcan.receive" => "`bxcan` `Can::receive`, one frame",
        "bxcan.rx0.receive" => "`bxcan` `Rx0::receive`, one frame",
        "equiv.tx" => "equivalent transmit: `Tx::transmit` (full: and the token)",
        "equiv.tx.one_busy" => "equivalent transmit, mailbox 0 busy",
        "equiv.tx_irq" => {
            "equivalent TX handler: `CAN_TSR` once, one loop, completion pushed, one \
             acknowledging store"
        }
        "equiv.rx_irq" => {
            "equivalent RX0 handler: `CAN_RDT0R` + `Rx0::receive` into the ring with counts, \
             until `WouldBlock`"
        }
        "equiv.take" => "equivalent thread side: dequeue, `FMI` → the user's filter index",
        "equiv.take_completion" => "equivalent thread side: dequeue a completion",
        "hand.tx" => "hand-written transmit into MB15",
        "hand.tx_irq" => "hand-written MB15 handler: completion pushed, flag acknowledged",
        "hand.rx_irq" => "hand-written Rx FIFO handler: one frame into the ring with counts",
        "hand.take" => "hand-written thread side: decode, `IDHIT` → the user's filter index",
        "hand.take_completion" => "hand-written thread side: dequeue a completion",
        _ => "",
    }
}

/// The smallest measurement of each region, summed.
fn sum(counts: &Counts, keys: &[&str]) -> Result<u64> {
    let mut n = 0;
    for k in keys {
        n += counts.net(k)?.0;
    }
    Ok(n)
}

fn ratio_f(a: u64, b: u64) -> f64 {
    if b == 0 {
        f64::NAN
    } else {
        a as f64 / b as f64
    }
}

fn case_label(c: &Case) -> String {
    format!("{} at {}", rate(c.bitrate), mhz(c.clock))
}

fn render_timing(s: &mut String, t: &[ControllerQuality]) {
    let _ = writeln!(s, "## 3. Bit-timing quality\n");
    let usual: Vec<String> = timing::BITRATES[..timing::USUAL_BITRATES]
        .iter()
        .map(|&r| rate(r))
        .collect();
    let odd: Vec<String> = timing::BITRATES[timing::USUAL_BITRATES..]
        .iter()
        .map(|&r| rate(r))
        .collect();
    let clocks: Vec<String> = timing::CLOCKS_MHZ.iter().map(|c| c.to_string()).collect();
    let _ = writeln!(
        s,
        "Grid: CAN clocks {} MHz × bit rates {} and the odd rates {} — {} cases per \
         controller — with the CiA sample point target (`cia_sample_point`: 87.5 % up to \
         500 kbit/s, 80 % up to 800 kbit/s, 75 % above). For each case, \
         `twocan_core::timing::solve` is compared with an exhaustive search over every \
         (prescaler, tseg1, tseg2) the controller's `Limits` allow, written in \
         `bench/src/timing.rs` from the objective documented in `docs/bit-timing.md`: \
         smallest bit rate error, then sample point closest to the target (exact \
         rationals), then more quanta, then smaller prescaler, then the earlier sample \
         point. \"Accepted\" means within the default tolerance of 1,000 ppm (what the \
         backends require); the ppm figure is `Timing::ppm_from_wished`, the sample \
         point error is the exact distance |(1 + tseg1) / quanta − target| in per \
         mille.\n",
        clocks.join(", "),
        usual.join(", "),
        odd.join(", "),
        timing::CLOCKS_MHZ.len() * timing::BITRATES.len()
    );
    let _ = writeln!(
        s,
        "| controller | solver = exhaustive | accepted (≤ 1,000 ppm) | worst ppm, accepted cases | worst ppm, all cases | worst sample point error, accepted cases | worst sample point error, all cases |\n\
         |---|---:|---:|---|---|---|---|"
    );
    for q in t {
        let n = q.cases.len();
        let worst_ppm = |c: Option<&Case>| {
            c.map(|c| {
                format!(
                    "{} ppm ({})",
                    thousands(c.ppm().unwrap_or(0)),
                    case_label(c)
                )
            })
            .unwrap_or_else(|| "–".into())
        };
        let worst_sp = |c: Option<&Case>| {
            c.map(|c| {
                format!(
                    "{:.1} ‰ ({})",
                    c.sample_point_error().unwrap_or(0.0),
                    case_label(c)
                )
            })
            .unwrap_or_else(|| "–".into())
        };
        let _ = writeln!(
            s,
            "| {} | {} / {} ({:.1} %) | {} / {} | {} | {} | {} | {} |",
            q.name,
            q.matching(),
            n,
            100.0 * q.matching() as f64 / n as f64,
            q.accepted(),
            n,
            worst_ppm(q.worst_ppm(Case::accepted)),
            worst_ppm(q.worst_ppm(|_| true)),
            worst_sp(q.worst_sample_point(Case::accepted)),
            worst_sp(q.worst_sample_point(|_| true)),
        );
    }
    let _ = writeln!(s);
    for q in t {
        let mismatches: Vec<&Case> = q.cases.iter().filter(|c| !c.matches()).collect();
        if mismatches.is_empty() {
            let _ = writeln!(
                s,
                "{}: the solver's choice equals the exhaustive search's in every case.\n",
                q.name
            );
        } else {
            let _ = writeln!(
                s,
                "{} cases where the solver differs from the exhaustive search \
                 (prescaler, tseg1, tseg2):\n",
                q.name
            );
            for c in mismatches {
                let _ = writeln!(
                    s,
                    "- {}: solver {:?}, exhaustive {:?}",
                    case_label(c),
                    c.solved
                        .as_ref()
                        .map(|t| (t.prescaler, t.tseg1(), t.tseg2())),
                    c.best.map(|b| (b.prescaler, b.tseg1, b.tseg2))
                );
            }
            let _ = writeln!(s);
        }
        let refused: Vec<String> = q
            .cases
            .iter()
            .filter(|c| !c.accepted())
            .map(|c| {
                format!(
                    "{} ({} ppm)",
                    case_label(c),
                    thousands(c.ppm().unwrap_or(0))
                )
            })
            .collect();
        if !refused.is_empty() {
            let _ = writeln!(
                s,
                "<details><summary>{}: the {} cases outside 1,000 ppm</summary>\n\n\
                 The best timing the controller allows is still too far from the wished \
                 rate (the exhaustive search finds nothing closer); the backends refuse \
                 these: {}.\n\n</details>\n",
                q.name,
                refused.len(),
                refused.join(", ")
            );
        }
    }
    let _ = writeln!(
        s,
        "Host time: solver over the whole grid {}; exhaustive search {}.\n",
        t.iter()
            .map(|q| format!("{} {:.3} ms", q.name, q.solver_secs * 1e3))
            .collect::<Vec<_>>()
            .join(", "),
        t.iter()
            .map(|q| format!("{} {:.2} s", q.name, q.exhaustive_secs))
            .collect::<Vec<_>>()
            .join(", ")
    );
}

fn render_sim(s: &mut String, sim: &[SimRow]) {
    let _ = writeln!(s, "## 4. Simulator speed\n");
    let _ = writeln!(
        s,
        "Simulated frames delivered per host second with the `twocan-sim` crate \
         (bus at {}; the bit rate only converts bit times to seconds). Each scenario is run \
         {} times; each trial runs batches until at least {:.1} s of host time have \
         passed. The count is of frames delivered to a receiver (the listener's received \
         frames, or frames taken from a driver's receive ring); the time includes building \
         and queueing them. Built with `--release`; single-threaded. The table gives the \
         median trial and the range over the trials (the host is shared with whatever \
         else runs on it).\n\n\
         Each scenario also runs forced onto the bit-level path (`Bus::set_fast_path(false)`: \
         every attempt played bit by bit, as with faults or arbitration ties), in the same \
         run with the trials interleaved; the last column is the fast path's median over \
         the bit-level path's. Each run checks that it took the path asked for (fast-path \
         attempts counted, none when forced off). Targets (issue 14): at least 1,000,000 \
         frames/s on the bare bus, 500,000 with both real drivers over their models.\n",
        rate(simspeed::BITRATE),
        simspeed::TRIALS,
        simspeed::MIN_SECS
    );
    let _ = writeln!(
        s,
        "| scenario | frames (median trial) | host time | **frames / s** (median) | range of the trials | simulated time / host time | bit-level path: frames / s (median) | **fast / bit-level** |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|"
    );
    for r in sim {
        let t = &r.fast;
        let m = t.median();
        let (lo, hi) = t.range();
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} s | **{}** | {} – {} | {:.1} × | {} | **{:.2} ×** |",
            t.scenario(),
            thousands(m.frames),
            m.secs,
            thousands(m.frames_per_sec().round() as u64),
            thousands(lo.round() as u64),
            thousands(hi.round() as u64),
            m.speedup(),
            thousands(r.bit_level.median().frames_per_sec().round() as u64),
            r.ratio()
        );
    }
    let _ = writeln!(s);
}

fn render_sources(s: &mut String) {
    let _ = writeln!(s, "## Where the measurements come from\n");
    let _ = writeln!(
        s,
        "| what | source |\n|---|---|\n\
         | the command, the report, section sizes, issue-21 figures, bit-timing grid and \
         exhaustive search, simulator scenarios | `bench/src/` (package `twocan-bench`, \
         binary `can-bench`) |\n\
         | loop-back firmwares (STM32F7, Teensy 3.6), lean and full | \
         `bench/firmware/loopback-twocan`, `loopback-bxcan`, `loopback-bxcan-equiv`, \
         `loopback-async`, `loopback-flexcan`, `loopback-flexcan-hand`; start-up \
         `bench/firmware/shared/stm32f7.rs`, `shared/kinetis.rs` |\n\
         | the variants and the equivalents | `bench/firmware/shared/bxcan_variant.rs`, \
         `flexcan_variant.rs`, `bxcan_equiv.rs`, `flexcan_hand.rs` |\n\
         | instruction-count and stack firmwares (QEMU mps2-an386) | \
         `bench/firmware/insn-count`, `insn-count-equiv`, `insn-count-flexcan`, \
         `insn-count-async`; `shared/ram_bxcan_crate.rs`, \
         `shared/qemu.rs` (markers, stack painting), `shared/ram_can.rs`, \
         `shared/ram_flexcan.rs`, `shared/flag_waker.rs` |\n\
         | QEMU plugin | `bench/plugin/insn_count.c` |\n\
         | firmware examples | `examples/*` (see `docs/firmware.md`); their stacks: \
         `can-fil --stack` (`fil/src/stack.rs`) |\n\n\
         The bench firmware is its own cargo workspace (`bench/firmware/Cargo.toml`, \
         excluded from the main workspace, with its own `Cargo.lock`), built by can-bench \
         with `cargo build --profile release|release-speed --target {TARGET} \
         --manifest-path bench/firmware/Cargo.toml` into `target/bench-firmware/` (one \
         invocation per feature set: the rest, the async firmwares, the lean variant, the \
         full variant, whose ELFs are copied to `<name>-lean` and `<name>-full`); the \
         examples are built into `target/bench-examples/`, the plugin into \
         `target/bench-plugin/`, can-fil into `fil/target/`.\n"
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn number_formats() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(1_000), "1,000");
        assert_eq!(thousands(1_234_567), "1,234,567");
        assert_eq!(ratio(10, 4), "2.50");
        assert_eq!(ratio(1, 0), "–");
        assert_eq!(rate(1_000_000), "1 Mbit/s");
        assert_eq!(rate(500_000), "500 kbit/s");
        assert_eq!(rate(33_333), "33,333 bit/s");
        assert_eq!(delta(1_205, 3), "+1,202");
        assert_eq!(delta(3, 5), "−2");
        assert_eq!(delta(4, 4), "±0");
    }

    #[test]
    fn every_one_feature_variant_says_what_it_switches() {
        for backend in Backend::ALL {
            for (_, feature) in firmware::FEATURE_VARIANTS {
                assert!(
                    !feature_note(backend, feature).is_empty(),
                    "{feature} of {}",
                    backend.name()
                );
            }
            assert!(feature_note(backend, "frob").is_empty());
        }
    }

    #[test]
    fn sim_rows_give_the_ratio_to_the_bit_level_path() {
        let speed = |frames: u64| simspeed::Speed {
            scenario: "bare bus".into(),
            frames,
            secs: 0.5,
            bus_secs: 1.0,
        };
        let trials = |f: [u64; 3]| simspeed::Trials {
            runs: f.iter().map(|&n| speed(n)).collect(),
        };
        // Medians: 500,000 and 125,000 frames/s.
        let row = SimRow {
            fast: trials([240_000, 250_000, 300_000]),
            bit_level: trials([62_500, 60_000, 70_000]),
        };
        assert!((row.ratio() - 4.0).abs() < 1e-9);
        let mut s = String::new();
        render_sim(&mut s, &[row]);
        assert!(s.contains("| fast / bit-level |") || s.contains("**fast / bit-level**"));
        assert!(
            s.contains("| **500,000** | 480,000 – 600,000 | 2.0 × | 125,000 | **4.00 ×** |"),
            "{s}"
        );
    }
}
