//! `docs/benchmarks.md`: every figure of one run, with the machine, the tools and the
//! method behind each.

use std::fmt::Write as _;

use crate::cmd::{self, Result};
use crate::firmware::{self, Paths, TARGET};
use crate::qemu::{self, Counts, Tools};
use crate::simspeed::{self, SimRow};
use crate::sizes::{Size, StateFigures};
use crate::timing::{self, Case, ControllerQuality};

/// The loop-back comparison of one build profile.
pub struct SizeBuild {
    /// Cargo profile.
    pub profile: String,
    /// Its opt-level.
    pub opt: String,
    /// `loopback-twocan`.
    pub ours: Size,
    /// `loopback-bxcan` (the bare `bxcan` crate).
    pub theirs: Size,
    /// `loopback-bxcan-equiv` (the `bxcan` crate and the service work of our features).
    pub equiv: Size,
    /// `loopback-async` (our driver through its async API).
    pub async_fw: Size,
}

/// The loop-back comparison.
pub struct SizeSection {
    /// One comparison per profile (the first is the headline).
    pub builds: Vec<SizeBuild>,
    /// What `loopback-twocan`'s `State` static holds.
    pub state: StateFigures,
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
    /// Its memory use.
    pub size: Size,
}

/// The firmware examples.
pub struct ExampleSection {
    /// Every binary built.
    pub builds: Vec<ExampleBuild>,
}

/// The instruction counts.
pub struct InsnSection {
    /// QEMU and gcc.
    pub tools: Tools,
    /// (opt-level, counts) per firmware build.
    pub runs: Vec<(String, Counts)>,
    /// (opt-level, counts) of `insn-count-async` per build.
    pub async_runs: Vec<(String, Counts)>,
    /// The marker window address.
    pub window: u32,
}

/// Everything measured.
pub struct Report {
    paths: Paths,
    /// Loop-back sizes.
    pub sizes: Option<SizeSection>,
    /// Example sizes.
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
fn thousands(n: u64) -> String {
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

    fn render_async(&self, s: &mut String, insn: &InsnSection) -> Result<()> {
        let _ = writeln!(s, "### Async receive path (issue 11)\n");
        let _ = writeln!(
            s,
            "`bench/firmware/insn-count-async`: the same driver and register stand-in, built \
             with twocan-core's `async` feature (a cargo invocation of its own, so the \
             feature does not reach the other firmwares). One frame through the async API \
             as an executor drives it: the task polls its `Rx::recv` future on an empty ring \
             (it registers its waker: `Pending`), the RX0 handler moves one frame into the \
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
            .map(|(opt, c)| {
                Ok(format!(
                    "{} at opt {opt}",
                    thousands(sum(c, &["twocan.rx_irq", "twocan.rx.receive"])?)
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
                let _ = writeln!(
                    s,
                    "- opt {}: flash **{}** B (RAM {} B), against {} B for the non-async \
                     `loopback-twocan`;",
                    b.opt,
                    thousands(b.async_fw.flash()),
                    thousands(b.async_fw.ram()),
                    thousands(b.ours.flash())
                );
            }
            let echo: Vec<String> = self
                .examples
                .iter()
                .flat_map(|e| e.builds.iter())
                .filter(|b| b.bin == "async_echo")
                .map(|b| {
                    format!(
                        "`{}` ({}): flash **{}** B, RAM {} B",
                        b.package,
                        b.board.as_deref().unwrap_or("no feature"),
                        thousands(b.size.flash()),
                        thousands(b.size.ram())
                    )
                })
                .collect();
            if echo.is_empty() {
                let _ = writeln!(
                    s,
                    "- the `async_echo` firmware examples were not among the examples built \
                     in this run (section 1, \"Firmware examples\"), so their flash is not \
                     given here.\n"
                );
            } else {
                let _ = writeln!(s, "- the `async_echo` examples: {}.\n", echo.join("; "));
            }
        }
        Ok(())
    }

    /// `target/bench/summary.json` (issue 10): the ratios ours / theirs as floats and the
    /// driver state's RAM; `None` unless both the sizes and the instruction counts (opt s
    /// and opt 3) were measured.
    pub fn summary(&self) -> Result<Option<serde_json::Value>> {
        let (Some(sizes), Some(insn)) = (&self.sizes, &self.insn) else {
            return Ok(None);
        };
        let run = |opt: &str| insn.runs.iter().find(|(o, _)| o == opt).map(|(_, c)| c);
        let (Some(s), Some(o3)) = (run("s"), run("3")) else {
            return Ok(None);
        };
        let Some(size_s) = sizes.builds.iter().find(|b| b.opt == "s") else {
            return Ok(None);
        };
        let r = |c: &Counts, t: &Target| -> Result<f64> {
            Ok(ratio_f(sum(c, t.ours)?, sum(c, t.theirs)?))
        };
        let [tx, rx, rt] = &TARGETS;
        let mut counts = serde_json::Map::new();
        for (opt, c) in &insn.runs {
            for t in &TARGETS {
                let key = |side: &str| {
                    format!(
                        "{}_{side}_{opt}",
                        t.tag.trim_matches(|c| c == '(' || c == ')')
                    )
                };
                counts.insert(key("ours"), sum(c, t.ours)?.into());
                counts.insert(key("theirs"), sum(c, t.theirs)?.into());
            }
        }
        Ok(Some(serde_json::json!({
            "tx_ratio_s": r(s, tx)?,
            "tx_ratio_3": r(o3, tx)?,
            "rx_isr_ratio_s": r(s, rx)?,
            "rx_isr_ratio_3": r(o3, rx)?,
            "roundtrip_ratio_s": r(s, rt)?,
            "roundtrip_ratio_3": r(o3, rt)?,
            "flash_ratio_equiv_s": ratio_f(size_s.ours.flash(), size_s.equiv.flash()),
            "flash_ratio_bare_s": ratio_f(size_s.ours.flash(), size_s.theirs.flash()),
            "ram_state_bytes": sizes.state.static_bytes - sizes.state.ring_bytes,
            "ram_ring_bytes": sizes.state.ring_bytes,
            "flash_bytes_s": {
                "twocan": size_s.ours.flash(),
                "bxcan": size_s.theirs.flash(),
                "bxcan_equiv": size_s.equiv.flash(),
            },
            "instructions": counts,
            "async_rx_path": insn
                .async_runs
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
            "flash_bytes_async_s": size_s.async_fw.flash(),
        })))
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
             the run took {:.0} s after can-bench itself was built, {:.0} s of it in cargo builds \
             of firmware (short when they were already built). Every figure in this file comes from that run — none is \
             written by hand. Run the command again to refresh it; a step that cannot run \
             stops the command with an error and leaves this file as it was.\n",
            self.elapsed_secs,
            self.build_secs
        );
        self.render_machine(&mut s);
        if let Some(sizes) = &self.sizes {
            self.render_sizes(&mut s, sizes, self.examples.as_ref());
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
        for krate in ["bxcan", "cortex-m", "cortex-m-rt", "cortex-m-semihosting"] {
            if let Some(v) = firmware::locked_version(&lock, krate) {
                let _ = writeln!(s, "| `{krate}` crate (bench firmware) | {v} |");
            }
        }
        let _ = writeln!(s, "| firmware target | `{TARGET}` |\n");
    }

    fn render_sizes(&self, s: &mut String, sz: &SizeSection, ex: Option<&ExampleSection>) {
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
             RAM) is not a section and is not counted.\n"
        );
        let _ = writeln!(
            s,
            "### Minimal loop-back firmware: our bxCAN backend against the `bxcan` crate\n"
        );
        let _ = writeln!(
            s,
            "Three firmwares for an STM32F767ZI with the same behaviour (`bench/firmware/`): \
             the same start-up (`shared/stm32f7.rs`: SYSCLK 108 MHz from the PLL, APB1 \
             54 MHz, CAN1 clock on), CAN1 in loop-back mode at 500 kbit/s from the 54 MHz \
             APB1 clock (the same `CAN_BTR`, solved at compile time), one accept-all filter \
             bank to FIFO 0 set by hand, one 8-byte frame sent and received by polling, \
             `panic-halt`.\n\n\
             - `loopback-twocan`: our split driver as an interrupt-driven application keeps \
             it — a `static State<BxCan<Mmio>, 8, FifoQueue<8>>` (all zeros, `.bss`; \
             request-order transmit, so no priority queue is linked), `split` once, \
             `Tx::try_send`, then the TX and RX0 handlers and `Rx::receive` polled in turn \
             until the frame comes back with its filter index and its completion;\n\
             - `loopback-bxcan`: the bare `bxcan` crate (`Can::builder`, `transmit`, \
             `receive`), the `Can` in a `critical_section::Mutex` static;\n\
             - `loopback-bxcan-equiv`: the `bxcan` crate plus the service work that gives \
             an application what ours does (**feature-equivalent**): a TX handler clearing \
             and counting completions (`clear_request_completed_flag` until `None`), an RX0 \
             handler draining FIFO 0 into a `heapless::Deque` of 8 frames, counting \
             hardware overruns and ring overflows and reading `CAN_ESR`, the thread side \
             taking the frame from the ring; the `Can` and the ring in one \
             `critical_section::Mutex` static.\n\n\
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
                "| firmware | code | data | bss | **flash** | **RAM** |\n\
                 |---|---:|---:|---:|---:|---:|"
            );
            for (name, z) in [
                ("`loopback-twocan` (twocan-bxcan, split driver)", &b.ours),
                ("`loopback-bxcan` (bare `bxcan` crate)", &b.theirs),
                (
                    "`loopback-bxcan-equiv` (`bxcan` crate, feature-equivalent)",
                    &b.equiv,
                ),
            ] {
                let _ = writeln!(
                    s,
                    "| {name} | {} | {} | {} | **{}** | **{}** |",
                    thousands(z.code()),
                    thousands(z.data()),
                    thousands(z.bss()),
                    thousands(z.flash()),
                    thousands(z.ram())
                );
            }
            for (label, t) in [("bare", &b.theirs), ("feature-equivalent", &b.equiv)] {
                let o = &b.ours;
                let _ = writeln!(
                    s,
                    "| ratio twocan / {label} | {} | {} | {} | **{}** | **{}** |",
                    ratio(o.code(), t.code()),
                    ratio(o.data(), t.data()),
                    ratio(o.bss(), t.bss()),
                    ratio(o.flash(), t.flash()),
                    ratio(o.ram(), t.ram())
                );
            }
            let _ = writeln!(s);
            let _ = writeln!(s, "Sections:\n");
            let _ = writeln!(s, "- `loopback-twocan`: {}", b.ours.section_list());
            let _ = writeln!(s, "- `loopback-bxcan`: {}", b.theirs.section_list());
            let _ = writeln!(s, "- `loopback-bxcan-equiv`: {}\n", b.equiv.section_list());
        }
        let st = &sz.state;
        let _ = writeln!(
            s,
            "**RAM of our driver**: the `State` static is {} B (symbol size of \
             `BENCH_CAN_STATE`), of which {} B are ring and queue slots (receive ring 8 raw \
             frames, transmit queue 8 entries, completion ring 8, state-change ring 8; the \
             same `State` type in `insn-count` reports them with `size_of`) and **{} B \
             driver state**: the controller value `BxCan<Mmio>` ({} B, of which {} B are \
             its filter map — user filter index per FIFO and filter match index, 2 × 112 \
             `u16`), the rest ring indices and statistics, counters and the transmit \
             queue's indices. The halves and handlers (`split`'s `Parts`) live wherever \
             the application keeps them; the receive half carries its own copy of the \
             filter map.\n",
            thousands(st.static_bytes),
            thousands(st.ring_bytes),
            thousands(st.static_bytes - st.ring_bytes),
            thousands(st.hw_bytes),
            thousands(st.fmi_bytes)
        );
        if let Some(b) = sz.builds.iter().find(|b| b.opt == "s") {
            let state = st.static_bytes - st.ring_bytes;
            let fe = ratio_f(b.ours.flash(), b.equiv.flash());
            let fb = ratio_f(b.ours.flash(), b.theirs.flash());
            let _ = writeln!(
                s,
                "**Target (d)** (opt s): flash ≤ 1.0 × the feature-equivalent firmware — \
                 {fe:.2} ({}); flash ≤ 1.5 × the bare one — {fb:.2} ({}); RAM = the rings + \
                 at most 64 B of state — {} B of state ({}).\n",
                verdict(fe, 1.0),
                verdict(fb, 1.5),
                thousands(state),
                if state <= 64 {
                    "met".to_string()
                } else {
                    format!("missed by {} B", thousands(state - 64))
                }
            );
            let _ = writeln!(
                s,
                "Why the flash target is missed (read from `llvm-objdump -d` and \
                 `llvm-nm --size-sort` of `loopback-twocan`): most of the difference is the \
                 configuration path, inlined into `main` — `Can::can1` with the `Config` \
                 checks and mode handshakes, a `FilterPlan` of 28 banks, the filter block \
                 programming and the filter map built from the plan — where the `bxcan` \
                 crate writes one bank's registers; then the transmit interrupt's service \
                 (`service_tx`: completion settling in acceptance order, the queue refill, \
                 the abort and displacement bookkeeping), and `compiler_builtins`' \
                 `memcpy`/`memset` (about 1.3 KB), linked because the controller value \
                 (with its filter map) and the filter plan are moved by value. The filter \
                 plan and map belong to the filter planner (`bxcan/src/filters.rs`, \
                 `filter_block.rs`); a plan and map sized for the banks in use, and a \
                 controller built in place inside the `State` (no move), are what would \
                 bring the flash and the state down. The state misses for the same reason: \
                 the filter map is the larger part of it.\n"
            );
        }

        let _ = writeln!(s, "### Firmware examples\n");
        match ex {
            None => {}
            Some(e) if e.builds.is_empty() => {
                let _ = writeln!(
                    s,
                    "No firmware example (a package under `examples/` with binaries and a \
                     `cortex-m-rt` dependency) exists yet, so none was measured.\n"
                );
            }
            Some(e) => {
                let _ = writeln!(
                    s,
                    "Every binary of every firmware package under `examples/` (binaries and a \
                     `cortex-m-rt` dependency), for each board feature, \
                     built with `cargo build --release --target {TARGET} -p PACKAGE \
                     --features BOARD --bins` (the workspace's release profile).\n"
                );
                let _ = writeln!(
                    s,
                    "| package | board | binary | code | data | bss | **flash** | **RAM** |\n\
                     |---|---|---|---:|---:|---:|---:|---:|"
                );
                for b in &e.builds {
                    let _ = writeln!(
                        s,
                        "| `{}` (`{}`) | {} | `{}` | {} | {} | {} | **{}** | **{}** |",
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
        }
    }

    fn render_insn(&self, s: &mut String, insn: &InsnSection) -> Result<()> {
        let _ = writeln!(s, "## 2. Instructions per frame on a Cortex-M4 (QEMU)\n");
        let _ = writeln!(
            s,
            "Guest instructions executed, counted by the TCG plugin \
             `bench/plugin/insn_count.c` (built at bench time with `gcc {}`) while QEMU \
             runs the firmware `bench/firmware/insn-count` on `-machine {}` (an ARM MPS2 \
             board with a Cortex-M4). This is an instruction count, not a cycle count: \
             QEMU does not model pipeline, wait states or bus timing.\n",
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
            "**Method.** QEMU's board has no bxCAN, so a RAM block at `0x2010_0000` stands in \
             for CAN1's registers: our driver reaches it through \
             `twocan_core::Mmio::new(0x2010_0000)`, the `bxcan` crate through its \
             `Instance::REGISTERS` pointer set to the same address. Both are configured \
             through their public APIs (loop-back, 500 kbit/s from 54 MHz, one accept-all \
             bank; request order for ours, the `bxcan` crate's identifier-priority order) while a SysTick handler plays the mode \
             handshake (`INRQ` → `INAK`, `SLEEP` → `SLAK`); SysTick is off before anything \
             is measured. RAM does not react like the peripheral (a write of `RFOM` does \
             not pop the FIFO, a write-1-to-clear store overwrites the whole word), so \
             **each measured call does exactly one frame's work from a freshly restored \
             snapshot** of the register block, showing what a real CAN1 would show, and \
             the firmware checks the effect afterwards (frame in the expected mailbox, \
             frame in the ring, FIFO released, completion counted); a failed check fails \
             the run. Snapshots: all mailboxes empty; mailbox 0 pending with a \
             lower-priority frame; all three pending with higher-priority frames (the \
             driver queues); mailbox 0 empty with its completion already acknowledged \
             (refill: on RAM the `RQCP` store would also clear the read-only `TME` bits); \
             mailbox 0 completed (`RQCP0`, `TXOK0`); FIFO 0 with one frame (`FMP0` = 1) — \
             each derived from the block as that driver's own configuration left it.\n"
        );
        let _ = writeln!(
            s,
            "A measurement counts the instructions executed after a start marker (a store \
             to the plugin's marker window at `{:#010x}`, outside every linker section) up \
             to and including the end marker store; each measured function is \
             `#[inline(never)]` and gets its arguments through `core::hint::black_box`, so \
             a figure includes its call and return. The instructions of an empty region \
             (start marker directly followed by the end marker) are subtracted. Each \
             region is measured {} times per build. The frame is a standard data frame, \
             identifier 0x123, 8 bytes. Our driver is a `static State<BxCan<Mmio>, 8, \
             FifoQueue<8>>` split once (`insn-count` exports its size); its handles are \
             the measured functions' arguments.\n",
            insn.window,
            insn.runs.first().map(|(_, c)| c.repeats()).unwrap_or(0)
        );
        let _ = writeln!(
            s,
            "### The targets of issue 10\n\n\
             Ratios are twocan / `bxcan`; ≤ 1.00 meets the target. (a) compares our \
             transmit half's direct path (queue empty, mailbox free: `Tx::try_send` writes \
             the mailbox) with `bxcan`'s `Can::transmit`; (b) our FIFO 0 receive interrupt \
             handler (`RxIrq::on_interrupt`: FIFO → raw ring, FIFO released) with \
             `bxcan`'s `Rx0::receive`, **one frame per interrupt** (the handler's \
             per-interrupt work is in the figure once); (c) the round trip as an \
             application sees it, summed over its steps: send, the TX interrupt settling \
             the completion, the RX0 interrupt, and the thread side taking the decoded \
             frame with its filter index — ours against the feature-equivalent service \
             around the `bxcan` crate (`transmit`; TX interrupt: \
             `clear_request_completed_flag` once with a completion and once without, \
             counting completions — the two calls of `clear_tx_interrupt`'s loop, each \
             on its own snapshot because RAM does not clear the flag; RX0 interrupt: \
             `Rx0::receive` until `WouldBlock` into a `heapless::spsc` ring (lock-free, \
             as ours), counting hardware overruns and ring overflows, reading `CAN_ESR`; \
             the thread side dequeuing the frame). The `bxcan` crate reports no filter \
             index, so its side does less there.\n"
        );
        let mut header = String::from("| | path | ");
        let mut rule = String::from("|---|---|");
        for (opt, _) in &insn.runs {
            let _ = write!(
                header,
                "twocan (opt {opt}) | bxcan (opt {opt}) | **ratio (opt {opt})** | "
            );
            rule.push_str("---:|---:|---:|");
        }
        header.push_str("target |");
        rule.push_str("---:|");
        let _ = writeln!(s, "{header}\n{rule}");
        for t in TARGETS {
            let mut line = format!("| {} | {} |", t.tag, t.label);
            for (_, counts) in &insn.runs {
                let (o, th) = (sum(counts, t.ours)?, sum(counts, t.theirs)?);
                let _ = write!(
                    line,
                    " {} | {} | **{}** |",
                    thousands(o),
                    thousands(th),
                    ratio(o, th)
                );
            }
            let _ = writeln!(s, "{line} ≤ 1.00 |");
        }
        let _ = writeln!(s);
        let mut verdicts = Vec::new();
        for t in TARGETS {
            let v: Vec<String> = insn
                .runs
                .iter()
                .map(|(opt, c)| {
                    Ok(format!(
                        "opt {opt}: {}",
                        verdict(ratio_f(sum(c, t.ours)?, sum(c, t.theirs)?), 1.0)
                    ))
                })
                .collect::<Result<_>>()?;
            verdicts.push(format!("{} {}", t.tag, v.join(", ")));
        }
        let _ = writeln!(s, "Verdicts: {}.\n", verdicts.join("; "));
        let _ = writeln!(
            s,
            "Where our instructions go (read from `llvm-objdump -d` of `insn-count`):\n\n\
             - (a) our direct path does work `Can::transmit` does not: it checks the \
             recorded error state (bus-off refuses the frame with an error), checks that \
             the transmit queue is empty (a frame never overtakes queued ones), stores the \
             frame's token for its completion and counts the accepted frame; and since \
             the register handle keeps its base address in the shared state, the compiler \
             reloads it after each volatile mailbox store (a store could alias it).\n\
             - (b) our handler loops until FIFO 0 is empty (so one frame per interrupt \
             reads `CAN_RF0R` twice), acknowledges `FULL0`/`FOVR0`, and stores the frame in \
             the ring: an acquire load of the consumer index and a release store of the \
             producer index (one `DMB` each on thumbv7em — kept because the ring must stay \
             sound between host threads and on multi-core parts), the ring's peak figure \
             and the received counter. `Rx0::receive` returns one frame to its caller and \
             stores nothing.\n\
             - (c) the transmit interrupt dominates: a critical section (the transmit \
             queue is the one structure two contexts modify), the completion — token, \
             outcome, time stamp — pushed into the completion ring (release/acquire as \
             above), the outcome counter, the abort and displacement flags, and the check \
             for queued frames to refill; the equivalent service only clears `RQCP0`. \
             The thread side decodes the raw words (identifier word, DLC clamp, data \
             cleared beyond the DLC) and maps the filter match index to the user's filter \
             index, which the `bxcan` crate does not report.\n"
        );
        let _ = writeln!(s, "### Every measured region\n");
        let mut header = String::from("| region | what is measured |");
        let mut rule = String::from("|---|---|");
        for (opt, _) in &insn.runs {
            let _ = write!(header, " opt {opt} |");
            rule.push_str("---:|");
        }
        let _ = writeln!(s, "{header}\n{rule}");
        let mut varying = Vec::new();
        for (key, what) in REGION_NOTES {
            let mut line = format!("| `{key}` | {what} |");
            for (opt, counts) in &insn.runs {
                let (lo, hi) = counts.net(key)?;
                if lo == hi {
                    let _ = write!(line, " {} |", thousands(lo));
                } else {
                    let _ = write!(line, " {} ({}–{}) |", thousands(lo), lo, hi);
                    varying.push(format!("`{key}` at opt {opt}"));
                }
            }
            let _ = writeln!(s, "{line}");
        }
        let _ = writeln!(s);
        let overheads: Vec<String> = insn
            .runs
            .iter()
            .map(|(opt, c)| format!("{} instruction(s) at opt-level {opt}", c.overhead))
            .collect();
        let _ = writeln!(
            s,
            "Each figure is the smallest of the region's {} measurements (the steady \
             state); {}. Marker overhead subtracted: {}. The firmware is built twice: \
             profile `release` (`opt-level = \"s\"`) and `release-speed` \
             (`opt-level = 3`), both with fat LTO and one codegen unit.\n",
            insn.runs.first().map(|(_, c)| c.repeats()).unwrap_or(0),
            if varying.is_empty() {
                "every measurement of every region was equal".to_string()
            } else {
                format!(
                    "where they differed the range is given ({}: the first measurement \
                     also raises a ring's peak figure, a store the later ones skip)",
                    varying.join(", ")
                )
            },
            overheads.join("; ")
        );
        self.render_async(s, insn)?;
        let _ = writeln!(s, "QEMU command line (per build):\n");
        let example = qemu::command(
            &insn.tools,
            std::path::Path::new("target/bench-firmware/thumbv7em-none-eabihf/release/insn-count"),
            std::path::Path::new("target/bench-plugin/insn_count.so"),
            insn.window,
            std::path::Path::new("target/bench-plugin/counts-release.txt"),
        );
        let line = cmd::display(&example)
            .replace(&insn.tools.qemu.display().to_string(), "qemu-system-arm");
        let _ = writeln!(s, "```\n{line}\n```\n");
        Ok(())
    }
}

/// One target of issue 10: regions summed on each side.
struct Target {
    tag: &'static str,
    label: &'static str,
    ours: &'static [&'static str],
    theirs: &'static [&'static str],
}

/// (a), (b), (c) of issue 10.
const TARGETS: [Target; 3] = [
    Target {
        tag: "(a)",
        label: "direct transmit: `Tx::try_send` / `Can::transmit`",
        ours: &["twocan.tx.direct"],
        theirs: &["bxcan.transmit"],
    },
    Target {
        tag: "(b)",
        label: "receive interrupt, one frame FIFO 0 → ring: `RxIrq::on_interrupt` / `Rx0::receive`",
        ours: &["twocan.rx_irq"],
        theirs: &["bxcan.rx0.receive"],
    },
    Target {
        tag: "(c)",
        label: "round trip: send + TX interrupt + RX0 interrupt + take the frame / the feature-equivalent `bxcan` service",
        ours: &[
            "twocan.tx.direct",
            "twocan.tx_irq.done",
            "twocan.rx_irq",
            "twocan.rx.receive",
        ],
        theirs: &[
            "bxcan.transmit",
            "equiv.tx_irq.clear",
            "equiv.tx_irq.idle",
            "equiv.rx_irq",
            "equiv.take",
        ],
    },
];

/// Every region of `insn-count` with what it measures.
const REGION_NOTES: [(&str, &str); 15] = [
    ("twocan.tx.direct", "`Tx::try_send`, all mailboxes empty, queue empty (direct path)"),
    ("twocan.tx.one_busy", "`Tx::try_send`, mailbox 0 busy (direct path into mailbox 1)"),
    ("twocan.tx.queued", "`Tx::try_send`, all mailboxes busy: the frame joins the queue (critical section)"),
    ("twocan.tx_irq.refill", "`TxIrq::on_interrupt`: queue → the mailbox freed"),
    ("twocan.tx_irq.done", "`TxIrq::on_interrupt`: one completion settled into the completion ring, nothing queued"),
    ("twocan.rx_irq", "`RxIrq::on_interrupt` (FIFO 0): one frame into the raw ring, FIFO released"),
    ("twocan.rx.receive", "`Rx::receive`: ring → decoded frame with filter index"),
    ("bxcan.transmit", "`bxcan` `Can::transmit`, all mailboxes empty"),
    ("bxcan.transmit.one_busy", "`bxcan` `Can::transmit`, mailbox 0 busy (lower priority)"),
    ("bxcan.receive", "`bxcan` `Can::receive`, one frame"),
    ("bxcan.rx0.receive", "`bxcan` `Rx0::receive`, one frame"),
    ("equiv.tx_irq.clear", "equivalent TX interrupt: `clear_request_completed_flag` → `Some`, counted"),
    ("equiv.tx_irq.idle", "equivalent TX interrupt: `clear_request_completed_flag` → `None` (ends the loop)"),
    ("equiv.rx_irq", "equivalent RX0 interrupt: one frame into the `heapless::spsc` ring, then `WouldBlock`; `CAN_ESR` read"),
    ("equiv.take", "equivalent thread side: `Consumer::dequeue`"),
];

/// The smallest measurement of each region, summed.
fn sum(counts: &Counts, keys: &[&str]) -> Result<u64> {
    let mut n = 0;
    for k in keys {
        n += counts.net(k)?.0;
    }
    Ok(n)
}

/// "met" or "missed by N %" for a ratio against its bound.
fn verdict(ratio: f64, bound: f64) -> String {
    if ratio <= bound {
        "met".into()
    } else {
        format!("missed by {:.0} %", 100.0 * (ratio / bound - 1.0))
    }
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
         | the command, the report, section sizes, bit-timing grid and exhaustive search, \
         simulator scenarios | `bench/src/` (package `twocan-bench`, binary `can-bench`) |\n\
         | loop-back firmwares (STM32F7) | `bench/firmware/loopback-twocan`, \
         `bench/firmware/loopback-bxcan`, `bench/firmware/loopback-bxcan-equiv`, \
         `bench/firmware/loopback-async`, `bench/firmware/shared/stm32f7.rs` |\n\
         | instruction-count firmwares (QEMU mps2-an386) | `bench/firmware/insn-count`, \
         `bench/firmware/insn-count-async`, `bench/firmware/shared/ram_can.rs`, \
         `bench/firmware/shared/flag_waker.rs` |\n\
         | QEMU plugin | `bench/plugin/insn_count.c` |\n\
         | firmware examples | `examples/*` (see `docs/firmware.md`) |\n\n\
         The bench firmware is its own cargo workspace (`bench/firmware/Cargo.toml`, \
         excluded from the main workspace, with its own `Cargo.lock`), built by can-bench \
         with `cargo build --profile release|release-speed --target {TARGET} \
         --manifest-path bench/firmware/Cargo.toml` into `target/bench-firmware/`; the \
         examples are built into `target/bench-examples/`, the plugin into \
         `target/bench-plugin/`.\n"
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
