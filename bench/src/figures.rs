//! The targets of issue 21 ("zero-cost by construction") computed from one run: each
//! figure ours against theirs per opt-level, with its bound, for the lean and the full
//! variant of each backend; and `target/bench/summary.json` built from them.

use crate::cmd::{Error, Result};
use crate::firmware::{FEATURE_VARIANTS, VARIANTS};
use crate::report::{ExampleSection, InsnSection, SizeSection};
use crate::sizes::StateFigures;

/// Which backend a figure is of.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    /// Our bxCAN driver against the `bxcan` crate (bare and feature-equivalent).
    BxCan,
    /// Our FlexCAN driver against the hand-written FlexCAN service.
    FlexCan,
}

impl Backend {
    /// Both, in report order.
    pub const ALL: [Backend; 2] = [Backend::BxCan, Backend::FlexCan];

    /// The instruction-count firmware.
    pub fn firmware(self) -> &'static str {
        match self {
            Backend::BxCan => "insn-count",
            Backend::FlexCan => "insn-count-flexcan",
        }
    }

    /// The instruction-count images whose runs make up its figures (merged).
    pub fn images(self) -> &'static [&'static str] {
        match self {
            Backend::BxCan => &["insn-count", "insn-count-equiv"],
            Backend::FlexCan => &["insn-count-flexcan"],
        }
    }

    /// Its name in the report.
    pub fn name(self) -> &'static str {
        match self {
            Backend::BxCan => "bxCAN",
            Backend::FlexCan => "FlexCAN",
        }
    }

    /// Key prefix in `summary.json` (`""` for bxCAN, the headline backend).
    pub fn key(self) -> &'static str {
        match self {
            Backend::BxCan => "",
            Backend::FlexCan => "flexcan_",
        }
    }

    /// The equivalent's round trip name and region prefix in its firmware.
    pub fn equivalent(self) -> &'static str {
        match self {
            Backend::BxCan => "equiv",
            Backend::FlexCan => "hand",
        }
    }

    /// Our loop-back firmware of this backend (flash, RAM and `State` figures).
    pub fn loopback(self) -> &'static str {
        match self {
            Backend::BxCan => "loopback-twocan",
            Backend::FlexCan => "loopback-flexcan",
        }
    }

    /// The board `can-fil` runs [`Backend::loopback`] on.
    pub fn board(self) -> &'static str {
        match self {
            Backend::BxCan => "nucleo-f767zi",
            Backend::FlexCan => "teensy36",
        }
    }

    /// The equivalent in prose.
    pub fn equivalent_label(self) -> &'static str {
        match self {
            Backend::BxCan => "the feature-equivalent `bxcan` service",
            Backend::FlexCan => "the hand-written FlexCAN service",
        }
    }

    /// The transmit the target compares ours with.
    fn tx_theirs(self) -> (&'static str, &'static str) {
        match self {
            Backend::BxCan => ("bxcan.transmit", "`bxcan` `Can::transmit`"),
            Backend::FlexCan => ("hand.tx", "the hand-written transmit"),
        }
    }
}

/// What a target measures in one opt-level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Measured {
    /// Ours over theirs (instructions or bytes).
    Ratio {
        /// Ours.
        ours: u64,
        /// Theirs.
        theirs: u64,
    },
    /// Bytes against a byte bound.
    Bytes(u64),
}

impl Measured {
    /// The ratio or the bytes as a number.
    pub fn value(&self) -> f64 {
        match *self {
            Measured::Ratio { ours, theirs } if theirs > 0 => ours as f64 / theirs as f64,
            Measured::Ratio { .. } => f64::NAN,
            Measured::Bytes(b) => b as f64,
        }
    }

    /// "met" or by how much it is missed against `bound`.
    pub fn verdict(&self, bound: f64) -> String {
        let v = self.value();
        if v <= bound {
            return "met".into();
        }
        match self {
            Measured::Ratio { .. } => format!("missed by {:.0} %", 100.0 * (v / bound - 1.0)),
            Measured::Bytes(b) => {
                format!("missed by {} B", crate::report::thousands(b - bound as u64))
            }
        }
    }
}

/// One target of issue 21 (or an extra line without a bound).
#[derive(Debug, Clone)]
pub struct Target {
    /// Backend.
    pub backend: Backend,
    /// `lean` or `full`.
    pub variant: &'static str,
    /// Short key: `tx`, `rx_isr`, `rx_bare`, `roundtrip`, `flash`, `state`,
    /// `config_stack`.
    pub key: &'static str,
    /// What is compared, in prose.
    pub label: String,
    /// The bound (a ratio, or bytes for `state` and `config_stack`); `None` for an
    /// extra line.
    pub bound: Option<f64>,
    /// (opt-level, figure).
    pub per_opt: Vec<(String, Measured)>,
    /// Where the difference goes, measured (per opt-level where it differs): the
    /// round trip's steps, the send's or handler's count, the flash by crate, the
    /// driver state by part. Rendered for a missed bound.
    pub cause: Vec<String>,
}

impl Target {
    /// The figure at `opt`.
    pub fn at(&self, opt: &str) -> Option<&Measured> {
        self.per_opt.iter().find(|(o, _)| o == opt).map(|(_, m)| m)
    }
}

/// A round-trip step (region) whose count differs between a one-feature variant and
/// lean, or that only one of them runs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StepChange {
    /// The region.
    pub key: String,
    /// Its net count in the variant's round trip (`None`: not in it).
    pub ours: Option<u64>,
    /// Its net count in lean's round trip (`None`: not in it).
    pub lean: Option<u64>,
}

impl StepChange {
    /// The variant's count minus lean's (a step missing on one side counts 0 there).
    pub fn delta(&self) -> i64 {
        self.ours.unwrap_or(0) as i64 - self.lean.unwrap_or(0) as i64
    }
}

/// One opt-level of a one-feature variant against lean.
#[derive(Debug, Clone)]
pub struct FeatureOpt {
    /// Opt-level.
    pub opt: String,
    /// Round trip, instructions: (the variant, lean).
    pub roundtrip: (u64, u64),
    /// The steps that changed, in round-trip order.
    pub steps: Vec<StepChange>,
    /// Flash, driver + application (`loopback-twocan`): (the variant, lean).
    pub flash: (u64, u64),
    /// RAM of `loopback-twocan` (data + bss): (the variant, lean).
    pub ram: (u64, u64),
    /// Configuration stack (`twocan.config` of `insn-count`): (the variant, lean).
    pub config_stack: (u64, u64),
}

/// What one compile-time choice costs: its one-feature variant against lean (one of
/// our drivers; issue 21, "each with its measured cost").
#[derive(Debug, Clone)]
pub struct FeatureCost {
    /// Whose driver.
    pub backend: Backend,
    /// The variant (`lean+done` ...).
    pub variant: &'static str,
    /// Its cargo feature (`done` ...).
    pub feature: &'static str,
    /// Per opt-level, in build order.
    pub per_opt: Vec<FeatureOpt>,
    /// The `State` static: (the variant, lean).
    pub state: (StateFigures, StateFigures),
}

impl FeatureCost {
    /// The figures at `opt`.
    pub fn at(&self, opt: &str) -> Option<&FeatureOpt> {
        self.per_opt.iter().find(|o| o.opt == opt)
    }
}

/// Every figure of issue 21.
pub struct Figures {
    /// The targets, by backend and variant.
    pub targets: Vec<Target>,
    /// The cost of each compile-time choice, per backend ([`Backend::ALL`] order), in
    /// [`FEATURE_VARIANTS`] order.
    pub feature_costs: Vec<FeatureCost>,
    /// The largest configuration stack of every firmware example and bench firmware,
    /// and where it was measured.
    pub config_stack_max: Option<(u64, String)>,
}

/// The configuration stack bound (1 KB).
pub const CONFIG_STACK_BOUND: u64 = 1024;
/// The driver state allowed beyond the rings.
pub const STATE_BOUND: u64 = 64;

impl Figures {
    /// Computes every target from the instruction counts, the sizes and the examples.
    pub fn compute(
        insn: &InsnSection,
        sizes: &SizeSection,
        examples: Option<&ExampleSection>,
    ) -> Result<Figures> {
        let mut targets = Vec::new();
        let opts = insn.opts();
        for backend in Backend::ALL {
            let eq = backend.equivalent();
            for &variant in &VARIANTS {
                let lean = variant == "lean";
                let ratio_of = |f: &dyn Fn(&crate::qemu::Counts) -> Result<(u64, u64)>| {
                    opts.iter()
                        .map(|opt| {
                            let c = insn.get(backend, variant, opt)?;
                            let (ours, theirs) = f(c)?;
                            Ok((opt.clone(), Measured::Ratio { ours, theirs }))
                        })
                        .collect::<Result<Vec<_>>>()
                };
                let region = |c: &crate::qemu::Counts, k: &str| -> Result<u64> { Ok(c.net(k)?.0) };
                let (tx_theirs, tx_label) = backend.tx_theirs();
                if lean || backend == Backend::BxCan {
                    targets.push(Target {
                        backend,
                        variant,
                        key: "tx",
                        label: format!("direct transmit: `Tx::try_send` / {tx_label}"),
                        bound: lean.then_some(1.0),
                        per_opt: ratio_of(&|c| {
                            Ok((region(c, "twocan.tx.direct")?, region(c, tx_theirs)?))
                        })?,
                        cause: Vec::new(),
                    });
                    targets.push(Target {
                        backend,
                        variant,
                        key: "rx_isr",
                        label: format!(
                            "receive handler, one frame into the ring: `RxIrq::on_interrupt` \
                             / {}'s handler",
                            backend.equivalent_label()
                        ),
                        bound: lean.then_some(1.0),
                        per_opt: ratio_of(&|c| {
                            Ok((
                                region(c, "twocan.rx_irq")?,
                                region(c, &format!("{eq}.rx_irq"))?,
                            ))
                        })?,
                        cause: Vec::new(),
                    });
                }
                targets.push(Target {
                    backend,
                    variant,
                    key: "rx_overrun",
                    label: "receive handler, one frame with the FIFO's overrun flag set / the \
                            same frame without (error and overrun handling out of the hot \
                            path: the event is counted out of line, paid only when it \
                            happens; extra line)"
                        .into(),
                    bound: None,
                    per_opt: ratio_of(&|c| {
                        Ok((
                            region(c, "twocan.rx_irq.overrun")?,
                            region(c, "twocan.rx_irq")?,
                        ))
                    })?,
                    cause: Vec::new(),
                });
                if backend == Backend::BxCan {
                    targets.push(Target {
                        backend,
                        variant,
                        key: "rx_bare",
                        label: "receive handler / bare `bxcan` `Rx0::receive` (extra line)".into(),
                        bound: None,
                        per_opt: ratio_of(&|c| {
                            Ok((region(c, "twocan.rx_irq")?, region(c, "bxcan.rx0.receive")?))
                        })?,
                        cause: Vec::new(),
                    });
                }
                targets.push(Target {
                    backend,
                    variant,
                    key: "roundtrip",
                    label: format!(
                        "round trip (send{}, handlers, take{}) / {}",
                        if lean { "" } else { " with token" },
                        if lean { "" } else { ", completion taken" },
                        backend.equivalent_label()
                    ),
                    bound: Some(if lean { 1.0 } else { 1.5 }),
                    per_opt: ratio_of(&|c| Ok((c.roundtrip("twocan")?, c.roundtrip(eq)?)))?,
                    cause: Vec::new(),
                });
                let flash = sizes
                    .builds
                    .iter()
                    .map(|b| {
                        let v = b.variant(variant).ok_or_else(|| {
                            Error::new(format!("no {variant} loop-back sizes at opt {}", b.opt))
                        })?;
                        let (ours, theirs) = v.of(backend);
                        Ok((
                            b.opt.clone(),
                            Measured::Ratio {
                                ours: ours.app_flash(),
                                theirs: theirs.app_flash(),
                            },
                        ))
                    })
                    .collect::<Result<Vec<_>>>()?;
                targets.push(Target {
                    backend,
                    variant,
                    key: "flash",
                    label: format!(
                        "flash, driver + application (vector table and start-up left out) / {}",
                        backend.equivalent_label()
                    ),
                    bound: Some(if lean { 1.3 } else { 3.0 }),
                    per_opt: flash,
                    cause: Vec::new(),
                });
                if lean {
                    let st = sizes
                        .state(variant)
                        .ok_or_else(|| Error::new(format!("no {variant} state figures")))?;
                    let fig = st.of(backend);
                    targets.push(Target {
                        backend,
                        variant,
                        key: "state",
                        label: format!(
                            "driver state beyond the rings ({} B of ring and queue slots)",
                            fig.ring_bytes
                        ),
                        bound: Some(STATE_BOUND as f64),
                        per_opt: vec![("s".into(), Measured::Bytes(fig.state_bytes()))],
                        cause: Vec::new(),
                    });
                }
                targets.push(Target {
                    backend,
                    variant,
                    key: "config_stack",
                    label: "configuration stack (configure, start, split)".into(),
                    bound: Some(CONFIG_STACK_BOUND as f64),
                    per_opt: opts
                        .iter()
                        .map(|opt| {
                            let c = insn.get(backend, variant, opt)?;
                            Ok((opt.clone(), Measured::Bytes(c.stack("twocan.config")?)))
                        })
                        .collect::<Result<Vec<_>>>()?,
                    cause: Vec::new(),
                });
            }
        }
        for t in &mut targets {
            t.cause = cause(t, insn, sizes)?;
        }
        Ok(Figures {
            targets,
            feature_costs: {
                let mut costs = Vec::new();
                for backend in Backend::ALL {
                    costs.extend(feature_costs(insn, sizes, backend)?);
                }
                costs
            },
            config_stack_max: config_stack_max(insn, sizes, examples),
        })
    }

    /// The target `key` of `backend`, `variant`.
    pub fn get(&self, backend: Backend, variant: &str, key: &str) -> Option<&Target> {
        self.targets
            .iter()
            .find(|t| t.backend == backend && t.variant == variant && t.key == key)
    }

    /// Its value at `opt`.
    pub fn value(&self, backend: Backend, variant: &str, key: &str, opt: &str) -> Result<f64> {
        self.get(backend, variant, key)
            .and_then(|t| t.at(opt))
            .map(Measured::value)
            .ok_or_else(|| {
                Error::new(format!(
                    "no figure {key} of {} {variant} at opt {opt}",
                    backend.name()
                ))
            })
    }

    /// The new `summary.json` fields of issue 21.
    pub fn summary_fields(&self) -> Result<serde_json::Map<String, serde_json::Value>> {
        let mut m = serde_json::Map::new();
        let b = Backend::BxCan;
        let f = Backend::FlexCan;
        let float = |v: f64| serde_json::Value::from(v);
        for (name, backend, variant, key, opt) in [
            ("lean_tx_ratio_s", b, "lean", "tx", "s"),
            ("lean_tx_ratio_3", b, "lean", "tx", "3"),
            ("lean_rx_isr_ratio_s", b, "lean", "rx_isr", "s"),
            ("lean_rx_isr_ratio_3", b, "lean", "rx_isr", "3"),
            ("lean_roundtrip_ratio_s", b, "lean", "roundtrip", "s"),
            ("lean_roundtrip_ratio_3", b, "lean", "roundtrip", "3"),
            ("lean_flash_ratio_equiv_s", b, "lean", "flash", "s"),
            ("full_roundtrip_ratio_s", b, "full", "roundtrip", "s"),
            ("full_roundtrip_ratio_3", b, "full", "roundtrip", "3"),
            ("full_flash_ratio_equiv_s", b, "full", "flash", "s"),
            (
                "flexcan_lean_roundtrip_ratio_s",
                f,
                "lean",
                "roundtrip",
                "s",
            ),
            (
                "flexcan_lean_roundtrip_ratio_3",
                f,
                "lean",
                "roundtrip",
                "3",
            ),
            (
                "flexcan_full_roundtrip_ratio_s",
                f,
                "full",
                "roundtrip",
                "s",
            ),
        ] {
            m.insert(name.into(), float(self.value(backend, variant, key, opt)?));
        }
        let bytes = |backend, key| -> Result<serde_json::Value> {
            Ok(serde_json::Value::from(
                self.value(backend, "lean", key, "s")? as u64,
            ))
        };
        m.insert("lean_ram_state_bytes".into(), bytes(b, "state")?);
        m.insert(
            "config_stack_bytes_max".into(),
            self.config_stack_max
                .as_ref()
                .map(|(v, _)| serde_json::Value::from(*v))
                .unwrap_or(serde_json::Value::Null),
        );
        // The rest of the targets, for scripts: every ratio and byte figure by name.
        let mut all = serde_json::Map::new();
        for t in &self.targets {
            for (opt, v) in &t.per_opt {
                let key = format!("{}{}_{}_{}", t.backend.key(), t.variant, t.key, opt);
                let value = match v {
                    Measured::Ratio { ours, theirs } => serde_json::json!({
                        "ours": ours, "theirs": theirs, "ratio": v.value(),
                    }),
                    Measured::Bytes(b) => serde_json::Value::from(*b),
                };
                all.insert(key, value);
            }
        }
        m.insert("issue21".into(), serde_json::Value::Object(all));
        m.insert(
            "feature_costs".into(),
            self.feature_costs_json(Backend::BxCan)?,
        );
        m.insert(
            "flexcan_feature_costs".into(),
            self.feature_costs_json(Backend::FlexCan)?,
        );
        Ok(m)
    }

    /// The one-feature variants of `backend`.
    pub fn feature_costs_of(&self, backend: Backend) -> impl Iterator<Item = &FeatureCost> {
        self.feature_costs
            .iter()
            .filter(move |c| c.backend == backend)
    }

    /// `feature_costs` (bxCAN) and `flexcan_feature_costs`: per one-feature variant,
    /// the round trip at opt s and opt 3, the flash (driver + application) at opt s,
    /// the driver state beyond the rings and the whole `State` static, and the
    /// configuration stack (the larger of the two opt-levels).
    fn feature_costs_json(&self, backend: Backend) -> Result<serde_json::Value> {
        let mut m = serde_json::Map::new();
        for c in self.feature_costs_of(backend) {
            let at = |opt: &str| {
                c.at(opt)
                    .ok_or_else(|| Error::new(format!("no figures of {} at opt {opt}", c.variant)))
            };
            let (s, three) = (at("s")?, at("3")?);
            m.insert(
                c.variant.into(),
                serde_json::json!({
                    "roundtrip_s": s.roundtrip.0,
                    "roundtrip_3": three.roundtrip.0,
                    "flash_equiv_s": s.flash.0,
                    "state_bytes": c.state.0.state_bytes(),
                    "state_static_bytes": c.state.0.static_bytes,
                    "config_stack_bytes": c.per_opt.iter().map(|o| o.config_stack.0).max(),
                }),
            );
        }
        Ok(serde_json::Value::Object(m))
    }
}

/// Where a target's difference goes, measured: for an instruction target the regions
/// of each side (per round-trip step for the round trip), for flash the code of each
/// side by crate, for the driver state the state's parts. One line per opt-level for
/// the measured ones; empty for a target without a bound.
fn cause(t: &Target, insn: &InsnSection, sizes: &SizeSection) -> Result<Vec<String>> {
    let mut lines = Vec::new();
    if t.bound.is_none() {
        return Ok(lines);
    }
    let eq = t.backend.equivalent();
    match t.key {
        "roundtrip" => {
            for (opt, _) in &t.per_opt {
                let c = insn.get(t.backend, t.variant, opt)?;
                let mut steps: Vec<(u8, &'static str, i64, i64)> = Vec::new();
                for (side, name) in [(0, "twocan"), (1, eq)] {
                    for k in c.roundtrip_keys(name)? {
                        let (n, label) = step_of(k);
                        let v = c.net(k)?.0 as i64;
                        match steps.iter_mut().find(|s| s.0 == n) {
                            Some(s) if side == 0 => s.2 += v,
                            Some(s) => s.3 += v,
                            None if side == 0 => steps.push((n, label, v, 0)),
                            None => steps.push((n, label, 0, v)),
                        }
                    }
                }
                steps.sort_by_key(|s| s.0);
                let parts: Vec<String> = steps
                    .iter()
                    .map(|(_, label, o, th)| {
                        format!("{label} {o} / {th} ({})", crate::report::signed(o - th))
                    })
                    .collect();
                lines.push(format!("opt {opt}: {}", parts.join(", ")));
            }
        }
        "flash" => {
            for b in &sizes.builds {
                let Some(v) = b.variant(t.variant) else {
                    continue;
                };
                let (ours, theirs) = v.of(t.backend);
                let list = |z: &crate::sizes::Size| {
                    z.code_by_crate
                        .iter()
                        .filter(|(_, n)| *n >= 32)
                        .map(|(k, n)| format!("{k} {}", crate::report::thousands(*n)))
                        .collect::<Vec<_>>()
                        .join(", ")
                };
                let largest = |z: &crate::sizes::Size| {
                    z.largest
                        .iter()
                        .map(|(k, n)| format!("`{k}` {}", crate::report::thousands(*n)))
                        .collect::<Vec<_>>()
                        .join(", ")
                };
                lines.push(format!(
                    "opt {}: {} B more; code by crate, ours: {}; theirs: {}; largest \
                     functions, ours: {}; theirs: {}",
                    b.opt,
                    crate::report::thousands(ours.app_flash().saturating_sub(theirs.app_flash())),
                    list(ours),
                    list(theirs),
                    largest(ours),
                    largest(theirs)
                ));
            }
        }
        "state" => {
            if let Some(st) = sizes.state(t.variant) {
                let f = st.of(t.backend);
                let fp = &f.footprint;
                let inside = [
                    f.fmi_bytes.map(|b| format!("filters {b}")),
                    f.system_bytes.map(|b| format!("pin plan {b}")),
                ]
                .into_iter()
                .flatten()
                .collect::<Vec<_>>();
                lines.push(format!(
                    "controller {} B{}, ring bookkeeping {} B (4 rings × 16 B, rings of \
                     capacity 0 included), queue bookkeeping {} B, time-stamp clock {} B, \
                     statistics {} B, rare-event counts {} B, wakers {} B, padding {} B",
                    fp.controller,
                    if inside.is_empty() {
                        String::new()
                    } else {
                        format!(" (of which {})", inside.join(", "))
                    },
                    fp.ring_bookkeeping,
                    fp.queue_bookkeeping,
                    fp.clock,
                    fp.statistics,
                    fp.errors,
                    fp.wakers,
                    fp.padding
                ));
            }
        }
        "tx" | "rx_isr" => {
            for (opt, m) in &t.per_opt {
                if let Measured::Ratio { ours, theirs } = m {
                    lines.push(format!(
                        "opt {opt}: {ours} / {theirs} instructions ({})",
                        crate::report::signed(*ours as i64 - *theirs as i64)
                    ));
                }
            }
        }
        _ => {}
    }
    Ok(lines)
}

/// The step of a round trip a region is (send, handlers, takes), for lining ours up
/// with the equivalent's: (order, label).
pub fn step_of(key: &str) -> (u8, &'static str) {
    if key.contains("tx_irq") {
        (1, "transmit handler (completion)")
    } else if key.contains("rx_irq") {
        (2, "receive handler (one frame)")
    } else if key.contains("take_completion") {
        (4, "completion taken")
    } else if key.ends_with(".receive") || key.ends_with(".take") {
        (3, "frame taken (with filter index)")
    } else {
        (0, "send")
    }
}

/// The one-feature variants of `b`'s driver against lean: round trips and their changed
/// steps and the configuration stack from its instruction-count firmware, flash and RAM
/// from its loop-back firmware, the `State` figures from both.
fn feature_costs(insn: &InsnSection, sizes: &SizeSection, b: Backend) -> Result<Vec<FeatureCost>> {
    let lean_states = sizes
        .state("lean")
        .ok_or_else(|| Error::new("no lean state figures"))?;
    let lean_state = *lean_states.of(b);
    let mut costs = Vec::new();
    for (variant, feature) in FEATURE_VARIANTS {
        let state = sizes
            .feature_states
            .iter()
            .find(|(fb, v, _)| *fb == b && v == variant)
            .map(|(_, _, st)| *st)
            .ok_or_else(|| Error::new(format!("no {variant} state figures")))?;
        let mut per_opt = Vec::new();
        for opt in insn.opts() {
            let ours = insn.get_feature(b, variant, &opt)?;
            let lean = insn.get(b, "lean", &opt)?;
            let ours_keys = ours.roundtrip_keys("twocan")?;
            let lean_keys = lean.roundtrip_keys("twocan")?;
            let mut keys: Vec<&String> = ours_keys.iter().collect();
            for k in lean_keys {
                if !keys.contains(&k) {
                    keys.push(k);
                }
            }
            let mut steps = Vec::new();
            for k in keys {
                let count = |c: &crate::qemu::Counts, in_it: &[String]| -> Result<Option<u64>> {
                    Ok(if in_it.contains(k) {
                        Some(c.net(k)?.0)
                    } else {
                        None
                    })
                };
                let change = StepChange {
                    key: k.clone(),
                    ours: count(ours, ours_keys)?,
                    lean: count(lean, lean_keys)?,
                };
                if change.ours != change.lean {
                    steps.push(change);
                }
            }
            let build = sizes
                .build(&opt)
                .ok_or_else(|| Error::new(format!("no loop-back sizes at opt {opt}")))?;
            let size = build
                .features
                .iter()
                .find(|(fb, v, _)| *fb == b && v == variant)
                .map(|(_, _, z)| z)
                .ok_or_else(|| Error::new(format!("no {variant} loop-back size at opt {opt}")))?;
            let lean_sizes = build
                .variant("lean")
                .ok_or_else(|| Error::new(format!("no lean loop-back sizes at opt {opt}")))?;
            let lean_size = lean_sizes.of(b).0;
            per_opt.push(FeatureOpt {
                opt: opt.clone(),
                roundtrip: (ours.roundtrip("twocan")?, lean.roundtrip("twocan")?),
                steps,
                flash: (size.app_flash(), lean_size.app_flash()),
                ram: (size.ram(), lean_size.ram()),
                config_stack: (ours.stack("twocan.config")?, lean.stack("twocan.config")?),
            });
        }
        costs.push(FeatureCost {
            backend: b,
            variant,
            feature,
            per_opt,
            state: (state, lean_state),
        });
    }
    Ok(costs)
}

/// The largest configuration stack: every `*.config` stack figure of every run of the
/// instruction-count firmwares (ours and the equivalents, both variants and our
/// drivers' one-feature variants, both profiles), every example's configuration
/// figure under can-fil, and every loop-back
/// firmware's whole run under can-fil (start-up, configuration and one polled frame:
/// they enable no interrupt line, so their whole run stands for their configuration).
fn config_stack_max(
    insn: &InsnSection,
    sizes: &SizeSection,
    examples: Option<&ExampleSection>,
) -> Option<(u64, String)> {
    let mut best: Option<(u64, String)> = None;
    let mut consider = |v: u64, what: String| {
        if best.as_ref().is_none_or(|(b, _)| v > *b) {
            best = Some((v, what));
        }
    };
    for r in insn.runs.iter().chain(&insn.feature_runs) {
        for (k, v) in &r.counts.stacks {
            if k.ends_with(".config") {
                consider(
                    *v,
                    format!(
                        "`{k}` of `{}` ({}, opt {})",
                        r.backend.firmware(),
                        r.variant,
                        r.opt
                    ),
                );
            }
        }
    }
    for r in &sizes.fil {
        consider(
            r.stack.whole,
            format!("loop-back firmware `{}` (opt {}, whole run)", r.elf, r.opt),
        );
    }
    for e in examples.into_iter().flat_map(|e| e.builds.iter()) {
        if let Some(c) = e.stack.and_then(|s| s.configuration) {
            consider(
                c,
                format!(
                    "example `{}` ({})",
                    e.bin,
                    e.board.as_deref().unwrap_or("no board feature")
                ),
            );
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts_say_by_how_much() {
        let r = Measured::Ratio {
            ours: 150,
            theirs: 100,
        };
        assert!((r.value() - 1.5).abs() < 1e-12);
        assert_eq!(r.verdict(1.5), "met");
        assert_eq!(r.verdict(1.0), "missed by 50 %");
        assert_eq!(Measured::Bytes(1100).verdict(1024.0), "missed by 76 B");
        assert_eq!(Measured::Bytes(3048).verdict(1024.0), "missed by 2,024 B");
        assert_eq!(Measured::Bytes(64).verdict(64.0), "met");
        assert!(Measured::Ratio { ours: 1, theirs: 0 }.value().is_nan());
    }

    #[test]
    fn a_step_only_one_side_runs_counts_zero_on_the_other() {
        let step = |ours, lean| StepChange {
            key: "twocan.tx_irq.done".into(),
            ours,
            lean,
        };
        assert_eq!(step(Some(50), None).delta(), 50);
        assert_eq!(step(None, Some(7)).delta(), -7);
        assert_eq!(step(Some(40), Some(43)).delta(), -3);
    }
}
