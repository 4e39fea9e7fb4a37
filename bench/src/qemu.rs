//! Instructions per frame under QEMU: the tools (QEMU, gcc), the counting plugin and the
//! run of the `insn-count` firmware.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use crate::cmd::{self, Context, Error, Result};
use crate::firmware::Paths;

/// The board QEMU emulates: a Cortex-M4 (ARM MPS2 with the AN386 FPGA image).
pub const MACHINE: &str = "mps2-an386";
/// Time allowed for one firmware run under QEMU.
const RUN_LIMIT: Duration = Duration::from_secs(120);
/// The ELF symbol holding the marker window address.
const WINDOW_SYMBOL: &str = "BENCH_MARKER_WINDOW";

/// The tools found (or installed) for this step.
#[derive(Debug, Clone)]
pub struct Tools {
    /// `qemu-system-arm`.
    pub qemu: PathBuf,
    /// Its `--version` first line.
    pub qemu_version: String,
    /// Whether can-bench installed QEMU in this run.
    pub qemu_installed_now: bool,
    /// `gcc`.
    pub gcc: PathBuf,
    /// Its `--version` first line.
    pub gcc_version: String,
    /// What `dpkg -S qemu-plugin.h` says about the installed packages.
    pub header_search: String,
}

fn is_root() -> bool {
    cmd::first_line("id", &["-u"]).as_deref() == Some("0")
}

fn apt_install(package: &str) -> Result<()> {
    if cmd::which("apt-get").is_none() {
        return Err(Error::new(format!(
            "`{package}` is missing and there is no apt-get to install it"
        )));
    }
    let install = || {
        let mut c = Command::new("apt-get");
        c.args(["install", "-y", "-q", package])
            .env("DEBIAN_FRONTEND", "noninteractive");
        eprintln!("can-bench: {}", cmd::display(&c));
        cmd::run_ok(&mut c, Duration::from_secs(900))
    };
    if install().is_ok() {
        return Ok(());
    }
    // The package lists may be missing or stale: update them once and retry.
    let mut update = Command::new("apt-get");
    update.args(["update", "-q"]);
    eprintln!("can-bench: {}", cmd::display(&update));
    cmd::run_ok(&mut update, Duration::from_secs(600)).context("apt-get update")?;
    install().context(format!("apt-get install -y {package}"))?;
    Ok(())
}

/// How to get a missing Debian package, for messages.
fn how_to_get(program: &str, package: &str) -> String {
    format!(
        "`{program}` is not installed: install the Debian package `{package}` \
         (`sudo apt-get install -y {package}`), or run `can-bench --install` as root to let \
         can-bench install it"
    )
}

/// Finds `program`. When it is missing, installs Debian `package` only if `install` is
/// set (`--install`) and can-bench runs as root; otherwise an error says what is missing
/// and how to get it.
fn ensure(program: &str, package: &str, install: bool) -> Result<(PathBuf, bool)> {
    if let Some(p) = cmd::which(program) {
        return Ok((p, false));
    }
    if !install {
        return Err(Error::new(how_to_get(program, package)));
    }
    if !is_root() {
        return Err(Error::new(format!(
            "{} (--install was given, but can-bench does not run as root: id -u is not 0)",
            how_to_get(program, package)
        )));
    }
    eprintln!(
        "can-bench: `{program}` not found; installing the Debian package `{package}` (--install)"
    );
    apt_install(package)?;
    let p = cmd::which(program).ok_or_else(|| {
        Error::new(format!(
            "`{program}` is still not in PATH after installing `{package}`"
        ))
    })?;
    Ok((p, true))
}

/// QEMU (with the mps2-an386 machine) and gcc; installed with apt-get only when `install`
/// (`--install`) is set.
pub fn tools(install: bool) -> Result<Tools> {
    let (qemu, qemu_installed_now) = ensure("qemu-system-arm", "qemu-system-arm", install)?;
    let qemu_s = qemu.to_string_lossy().into_owned();
    let qemu_version = cmd::first_line(&qemu_s, &["--version"])
        .ok_or_else(|| Error::new(format!("`{qemu_s} --version` failed")))?;
    let machines = cmd::run_ok(
        Command::new(&qemu).args(["-machine", "help"]),
        Duration::from_secs(30),
    )?;
    if !machines
        .stdout
        .lines()
        .any(|l| l.split_whitespace().next() == Some(MACHINE))
    {
        return Err(Error::new(format!(
            "{qemu_version} has no `{MACHINE}` machine (QEMU 6.0 or newer is needed)"
        )));
    }
    let (gcc, _) = ensure("gcc", "gcc", install)?;
    let gcc_version = cmd::first_line(&gcc.to_string_lossy(), &["--version"])
        .ok_or_else(|| Error::new("`gcc --version` failed"))?;
    Ok(Tools {
        qemu,
        qemu_version,
        qemu_installed_now,
        gcc,
        gcc_version,
        header_search: header_search(),
    })
}

/// Whether an installed Debian package ships QEMU's plugin header.
fn header_search() -> String {
    let mut c = Command::new("dpkg");
    c.args(["-S", "qemu-plugin.h"]);
    match cmd::run(&mut c, Duration::from_secs(60)) {
        Ok(o) if o.code == Some(0) => format!(
            "`dpkg -S qemu-plugin.h` found: {}",
            o.stdout.lines().collect::<Vec<_>>().join("; ")
        ),
        Ok(_) => "`dpkg -S qemu-plugin.h` finds no installed package with the header".into(),
        Err(_) => "`dpkg` is not available to search the installed packages".into(),
    }
}

/// The gcc command line that builds the plugin (for the report too).
pub const PLUGIN_FLAGS: [&str; 7] = [
    "-shared",
    "-fPIC",
    "-O2",
    "-fvisibility=hidden",
    "-Wall",
    "-Wextra",
    "-Werror",
];

/// Builds `bench/plugin/insn_count.c` into a shared object; returns its path.
pub fn build_plugin(paths: &Paths, tools: &Tools) -> Result<PathBuf> {
    let source = paths.root.join("bench").join("plugin").join("insn_count.c");
    let dir = paths.scratch("bench-plugin");
    std::fs::create_dir_all(&dir).context(format!("creating {}", dir.display()))?;
    let so = dir.join("insn_count.so");
    let mut c = Command::new(&tools.gcc);
    c.args(PLUGIN_FLAGS).arg("-o").arg(&so).arg(&source);
    eprintln!("can-bench: {}", cmd::display(&c));
    cmd::run_ok(&mut c, Duration::from_secs(120)).context("building the QEMU plugin")?;
    Ok(so)
}

/// One measured region.
#[derive(Debug, Clone)]
pub struct Region {
    /// Raw counts of each measurement (marker overhead included).
    pub raw: Vec<u64>,
}

/// The outcome of one firmware run.
#[derive(Debug, Clone, Default)]
pub struct Counts {
    /// Regions by key (`twocan.try_send.direct`, ... as the firmware names them).
    pub regions: BTreeMap<String, Region>,
    /// Instructions of an empty region (the end marker store), subtracted from the others.
    pub overhead: u64,
    /// Stack high-water marks by key (`stack <key> <bytes>` lines), bytes.
    pub stacks: BTreeMap<String, u64>,
    /// Other figures the firmware reported (`note <key> <value>`).
    pub notes: BTreeMap<String, u64>,
    /// The regions each round trip sums (`roundtrip <name> <keys...>`).
    pub roundtrips: BTreeMap<String, Vec<String>>,
    /// The build's variant (`variant <name>`), if it said.
    pub variant: Option<String>,
}

impl Counts {
    /// Net instructions of `key`: (min, max) over its measurements.
    pub fn net(&self, key: &str) -> Result<(u64, u64)> {
        let r = self
            .regions
            .get(key)
            .ok_or_else(|| Error::new(format!("the firmware measured no region `{key}`")))?;
        let min = r.raw.iter().min().copied().unwrap_or(0);
        let max = r.raw.iter().max().copied().unwrap_or(0);
        Ok((
            min.saturating_sub(self.overhead),
            max.saturating_sub(self.overhead),
        ))
    }

    /// The round trip `name` (as the firmware composed it): the sum of its regions.
    pub fn roundtrip(&self, name: &str) -> Result<u64> {
        let keys = self.roundtrip_keys(name)?;
        let mut n = 0;
        for k in keys {
            n += self.net(k)?.0;
        }
        Ok(n)
    }

    /// The regions of round trip `name`.
    pub fn roundtrip_keys(&self, name: &str) -> Result<&[String]> {
        self.roundtrips
            .get(name)
            .map(Vec::as_slice)
            .ok_or_else(|| Error::new(format!("the firmware declared no round trip `{name}`")))
    }

    /// A stack high-water mark, bytes.
    pub fn stack(&self, key: &str) -> Result<u64> {
        self.stacks
            .get(key)
            .copied()
            .ok_or_else(|| Error::new(format!("the firmware reported no stack figure `{key}`")))
    }

    /// Adds the figures of another run (another image of the same comparison): every
    /// key must be new, except the calibration region `empty`; measurements keep their
    /// net value (the other run's marker overhead is taken off, this one's added).
    pub fn merge(&mut self, other: Counts) -> Result<()> {
        if self.variant != other.variant {
            return Err(Error::new(format!(
                "merging runs of variants {:?} and {:?}",
                self.variant, other.variant
            )));
        }
        for (k, r) in other.regions {
            if k == "empty" {
                continue;
            }
            if self.regions.contains_key(&k) {
                return Err(Error::new(format!("region `{k}` measured by both runs")));
            }
            let raw = r
                .raw
                .iter()
                .map(|&c| c.saturating_sub(other.overhead) + self.overhead)
                .collect();
            self.regions.insert(k, Region { raw });
        }
        for (k, v) in other.stacks {
            if self.stacks.insert(k.clone(), v).is_some() {
                return Err(Error::new(format!("stack `{k}` reported by both runs")));
            }
        }
        for (k, v) in other.roundtrips {
            if self.roundtrips.insert(k.clone(), v).is_some() {
                return Err(Error::new(format!(
                    "round trip `{k}` declared by both runs"
                )));
            }
        }
        for (k, v) in other.notes {
            self.notes.entry(k).or_insert(v);
        }
        Ok(())
    }

    /// Measurements per region (the same for every region).
    pub fn repeats(&self) -> usize {
        self.regions
            .values()
            .map(|r| r.raw.len())
            .min()
            .unwrap_or(0)
    }
}

/// The QEMU command line for `elf` (for running and for the report).
pub fn command(tools: &Tools, elf: &Path, plugin: &Path, window: u32, out: &Path) -> Command {
    let mut c = Command::new(&tools.qemu);
    c.args(["-machine", MACHINE, "-cpu", "cortex-m4", "-nographic"])
        .args(["-monitor", "none", "-serial", "none"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .arg("-kernel")
        .arg(elf)
        .arg("-plugin")
        .arg(format!(
            "{},base={window:#x},outfile={}",
            plugin.display(),
            out.display()
        ));
    c
}

/// Runs the `insn-count` firmware `elf` under QEMU with the plugin and collects the counts.
pub fn run(paths: &Paths, tools: &Tools, plugin: &Path, elf: &Path, tag: &str) -> Result<Counts> {
    let window = crate::sizes::read_u32_symbol(elf, WINDOW_SYMBOL)?;
    let out_file = paths
        .scratch("bench-plugin")
        .join(format!("counts-{tag}.txt"));
    let _ = std::fs::remove_file(&out_file);
    let mut c = command(tools, elf, plugin, window, &out_file);
    eprintln!("can-bench: {}", cmd::display(&c));
    let out = cmd::run(&mut c, RUN_LIMIT).context("running the firmware under QEMU")?;
    let failed = out.stdout.lines().find(|l| l.starts_with("FAIL"));
    if out.code != Some(0) || failed.is_some() || !out.stdout.lines().any(|l| l == "done") {
        return Err(Error::new(format!(
            "the insn-count firmware failed under QEMU (exit {:?}){}\nstdout:\n{}\nstderr:\n{}",
            out.code,
            failed.map(|f| format!(": {f}")).unwrap_or_default(),
            cmd::tail(&out.stdout, 20),
            cmd::tail(&out.stderr, 20)
        )));
    }
    let counts = std::fs::read_to_string(&out_file).context(format!(
        "reading the plugin output {} (did the plugin load?)",
        out_file.display()
    ))?;
    parse(&out.stdout, &counts, window)
}

/// Pairs the firmware's region names (its semihosting output) with the plugin's counts,
/// and collects the firmware's stack figures, notes and round trips.
fn parse(stdout: &str, counts: &str, window: u32) -> Result<Counts> {
    let mut keys = BTreeMap::new();
    let mut stacks = BTreeMap::new();
    let mut notes = BTreeMap::new();
    let mut roundtrips = BTreeMap::new();
    let mut variant = None;
    for line in stdout.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["window", addr] => {
                let addr = u32::from_str_radix(addr.trim_start_matches("0x"), 16)
                    .context("firmware window line")?;
                if addr != window {
                    return Err(Error::new(format!(
                        "the firmware says its marker window is {addr:#x}, the ELF symbol \
                         {WINDOW_SYMBOL} says {window:#x}"
                    )));
                }
            }
            ["region", n, key] => {
                let n: u32 = n.parse().context("firmware region line")?;
                keys.insert(n, key.to_string());
            }
            ["stack", key, bytes] => {
                let bytes: u64 = bytes.parse().context("firmware stack line")?;
                stacks.insert(key.to_string(), bytes);
            }
            ["note", key, value] => {
                let value: u64 = value.parse().context("firmware note line")?;
                notes.insert(key.to_string(), value);
            }
            ["roundtrip", name, parts @ ..] if !parts.is_empty() => {
                roundtrips.insert(
                    name.to_string(),
                    parts.iter().map(|p| p.to_string()).collect::<Vec<_>>(),
                );
            }
            ["variant", name] => variant = Some(name.to_string()),
            _ => {}
        }
    }
    let mut regions: BTreeMap<String, Region> = BTreeMap::new();
    let mut finished = false;
    for line in counts.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["region", n, count] => {
                let n: u32 = n.parse().context("plugin output")?;
                let count: u64 = count.parse().context("plugin output")?;
                let key = keys.get(&n).ok_or_else(|| {
                    Error::new(format!(
                        "the plugin measured region {n}, which the firmware did not name"
                    ))
                })?;
                regions
                    .entry(key.clone())
                    .or_insert_with(|| Region { raw: Vec::new() })
                    .raw
                    .push(count);
            }
            ["total", t, "completed", _, "unmatched", u] => {
                if *u != "0" {
                    return Err(Error::new(format!(
                        "the plugin saw {u} end markers without a start"
                    )));
                }
                t.parse::<u64>().context("plugin output")?;
                finished = true;
            }
            _ => {}
        }
    }
    if !finished {
        return Err(Error::new(
            "the plugin output has no `total` line (QEMU did not exit normally)",
        ));
    }
    for key in keys.values() {
        if !regions.contains_key(key) {
            return Err(Error::new(format!("region `{key}` was never measured")));
        }
    }
    let empty = regions
        .get("empty")
        .ok_or_else(|| Error::new("no calibration region `empty`"))?;
    let overhead = *empty.raw.iter().min().unwrap_or(&0);
    if empty.raw.iter().any(|&c| c != overhead) {
        return Err(Error::new(format!(
            "the empty region was not constant: {:?}",
            empty.raw
        )));
    }
    for (name, parts) in &roundtrips {
        if let Some(k) = parts.iter().find(|k| !regions.contains_key(*k)) {
            return Err(Error::new(format!(
                "round trip `{name}` sums `{k}`, which the firmware did not measure"
            )));
        }
    }
    Ok(Counts {
        regions,
        overhead,
        stacks,
        notes,
        roundtrips,
        variant,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_tool_is_named_not_installed_without_install() {
        let e = ensure("twocan-no-such-program", "twocan-no-such-package", false)
            .expect_err("a missing program is an error");
        let msg = e.to_string();
        assert!(
            msg.contains("`twocan-no-such-program` is not installed"),
            "{msg}"
        );
        assert!(
            msg.contains("apt-get install -y twocan-no-such-package"),
            "{msg}"
        );
        assert!(msg.contains("can-bench --install"), "{msg}");
        // A present program is found and reported as not installed by this run.
        let (p, installed_now) = ensure("sh", "dash", false).unwrap();
        assert!(p.ends_with("sh") && !installed_now);
    }

    const STDOUT: &str = "window 0x20110000\nregion 0 empty\nregion 1 a.b\nregion 2 c\n\
                          roundtrip ours a.b c\nvariant lean\nstack a.b 24\n\
                          note cfg.low 8\ndone\n";

    #[test]
    fn pairs_names_and_counts_and_subtracts_the_empty_region() {
        let plugin = "window 0x20110000\nregion 0 1\nregion 1 11\nregion 0 1\nregion 1 11\n\
                      region 2 7\nregion 2 9\ntotal 500 completed 6 unmatched 0\n";
        let c = parse(STDOUT, plugin, 0x2011_0000).unwrap();
        assert_eq!(c.overhead, 1);
        assert_eq!(c.net("a.b").unwrap(), (10, 10));
        assert_eq!(c.net("c").unwrap(), (6, 8));
        assert_eq!(c.repeats(), 2);
        assert!(c.net("missing").is_err());
        // The round trip sums the smallest measurement of each of its regions.
        assert_eq!(c.roundtrip("ours").unwrap(), 10 + 6);
        assert!(c.roundtrip("theirs").is_err());
        assert_eq!(c.stack("a.b").unwrap(), 24);
        assert!(c.stack("c").is_err());
        assert_eq!(c.notes.get("cfg.low"), Some(&8));
        assert_eq!(c.variant.as_deref(), Some("lean"));
    }

    #[test]
    fn merges_a_second_run_keeping_net_values() {
        let a = parse(
            "region 0 empty\nregion 1 a\nvariant lean\nroundtrip ours a\nstack a 8\n",
            "region 0 1\nregion 1 11\ntotal 9 completed 2 unmatched 0\n",
            0x2011_0000,
        )
        .unwrap();
        let b = parse(
            "region 0 empty\nregion 1 b\nvariant lean\nroundtrip theirs b\nstack b 4\n",
            "region 0 3\nregion 1 10\ntotal 9 completed 2 unmatched 0\n",
            0x2011_0000,
        )
        .unwrap();
        let mut m = a.clone();
        m.merge(b.clone()).unwrap();
        assert_eq!(m.net("a").unwrap(), (10, 10));
        assert_eq!(m.net("b").unwrap(), (7, 7));
        assert_eq!(m.roundtrip("theirs").unwrap(), 7);
        assert_eq!(m.stack("b").unwrap(), 4);
        // The same key twice, or two variants, is refused.
        let mut twice = a.clone();
        assert!(twice.merge(a.clone()).is_err());
        let mut other = b;
        other.variant = Some("full".into());
        let mut m = a;
        assert!(m.merge(other).is_err());
    }

    #[test]
    fn refuses_a_round_trip_over_an_unmeasured_region() {
        let stdout = "region 0 empty\nregion 1 a\nroundtrip ours a b\n";
        let plugin = "region 0 1\nregion 1 3\ntotal 9 completed 2 unmatched 0\n";
        let e = parse(stdout, plugin, 0x2011_0000).unwrap_err();
        assert!(e.to_string().contains("`b`"), "{e}");
    }

    #[test]
    fn refuses_incomplete_or_inconsistent_output() {
        let complete = "region 0 1\nregion 1 5\nregion 2 5\n";
        // QEMU did not exit through the plugin's exit callback.
        assert!(parse(STDOUT, complete, 0x2011_0000).is_err());
        let done = format!("{complete}total 9 completed 3 unmatched 0\n");
        assert!(parse(STDOUT, &done, 0x2011_0000).is_ok());
        // Another window than the ELF symbol says.
        assert!(parse(STDOUT, &done, 0x2012_0000).is_err());
        // An end marker without a start.
        let unmatched = format!("{complete}total 9 completed 3 unmatched 1\n");
        assert!(parse(STDOUT, &unmatched, 0x2011_0000).is_err());
        // A named region that was never measured.
        let partial = "region 0 1\nregion 1 5\ntotal 9 completed 2 unmatched 0\n";
        assert!(parse(STDOUT, partial, 0x2011_0000).is_err());
        // A calibration region that varies.
        let varying = format!("region 0 2\n{done}");
        assert!(parse(STDOUT, &varying, 0x2011_0000).is_err());
    }
}
