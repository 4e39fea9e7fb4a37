//! `can-timing`: CAN bit timing calculator for FlexCAN and bxCAN.
//!
//! ```text
//! can-timing --controller flexcan|bxcan [--clock HZ] [--bus-clock HZ] --bitrate BPS
//!            [--sample-point PCT] [--tolerance PPM] [--json] [--all]
//! ```
//!
//! The timing is computed and judged by the rule the driver applies
//! (`twocan_core::timing::TimingRule`; FlexCAN: `flexcan_rules::rule` with the bus clock,
//! 8 quanta and 16 bus clocks per bit, as the FlexCAN backend's `begin`, `set_timing`,
//! `set_bitrate` and capabilities; bxCAN: the `CAN_BTR` ranges, as `Config::from_bitrate`
//! and the capabilities): what it accepts, the driver accepts.
//!
//! Exit status: 0 timing accepted (in the rule's range, allowed, within tolerance), 1
//! timing printed but refused: outside the tolerance (ACAN "too far from wished bit
//! rate"), a wished rate outside the rule's range (one bit per second beyond the
//! fastest or slowest accepted timing), or, for FlexCAN, forbidden by the Kinetis
//! manual's rules (bus clock not below the CAN clock, 16 bus clocks per bit); 2 bad
//! options or input, or no timing at all (a rate above clock / fewest quanta).

use std::process::ExitCode;

use clap::error::ErrorKind;
use clap::{CommandFactory, Parser, ValueEnum};
use serde::ser::{SerializeMap, Serializer};
use serde::Serialize;
use twocan_core::timing::{
    cia_sample_point, flexcan_rules, solve, Controller, Limits, Solutions, Timing, TimingError,
    TimingRule, DEFAULT_TOLERANCE_PPM, FLEXCAN_CTRL1_TIMING_MASK,
};

/// The controller whose bit timing register is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ControllerArg {
    /// NXP FlexCAN (CTRL1)
    Flexcan,
    /// STM32 bxCAN (CAN_BTR)
    Bxcan,
}

impl From<ControllerArg> for Controller {
    fn from(c: ControllerArg) -> Self {
        match c {
            ControllerArg::Flexcan => Controller::FlexCan,
            ControllerArg::Bxcan => Controller::BxCan,
        }
    }
}

/// CAN bit timing calculator for FlexCAN and bxCAN.
#[derive(Debug, Parser)]
#[command(
    name = "can-timing",
    version,
    after_help = "exit status: 0 ok, 1 outside tolerance, 2 bad options"
)]
struct Args {
    /// The controller
    #[arg(long, value_enum, ignore_case = true)]
    controller: ControllerArg,
    /// CAN clock in Hz (flexcan default 16000000, ACAN's CAN clock; bxcan: required, the
    /// APB1 clock, e.g. 54000000)
    #[arg(long, value_name = "HZ", value_parser = parse_u32)]
    clock: Option<u32>,
    /// FlexCAN: the peripheral (bus) clock in Hz, for the Kinetis manual's rule of 16
    /// bus clocks per CAN bit (default: the CAN clock, the least the manual allows)
    #[arg(long, value_name = "HZ", value_parser = parse_u32)]
    bus_clock: Option<u32>,
    /// Wished bit rate in bit/s
    #[arg(long, value_name = "BPS", value_parser = parse_u32)]
    bitrate: u32,
    /// Target sample point in per cent, e.g. 87.5 (default: CiA, 87.5 up to 500 kbit/s,
    /// 80 up to 800 kbit/s, 75 above)
    #[arg(long, value_name = "PCT", value_parser = parse_percent)]
    sample_point: Option<u16>,
    /// Accepted distance from the wished bit rate (0 = exact only)
    #[arg(long, value_name = "PPM", value_parser = parse_u32, default_value_t = DEFAULT_TOLERANCE_PPM)]
    tolerance: u32,
    /// Print one JSON object
    #[arg(long)]
    json: bool,
    /// Also list every timing within the tolerance
    #[arg(long)]
    all: bool,
}

struct Options {
    controller: Controller,
    clock: u32,
    bus_clock: u32,
    bitrate: u32,
    sample_point: Option<u16>,
    tolerance: u32,
    json: bool,
    all: bool,
}

impl Args {
    /// The options, with the clock defaulted per controller.
    fn options(&self) -> Result<Options, clap::Error> {
        let controller = Controller::from(self.controller);
        let clock = match (self.clock, controller) {
            (Some(c), _) => c,
            (None, Controller::FlexCan) => 16_000_000,
            (None, Controller::BxCan) => {
                return Err(Args::command().error(
                    ErrorKind::MissingRequiredArgument,
                    "--clock is required for bxcan (the APB1 clock in Hz)",
                ))
            }
        };
        Ok(Options {
            controller,
            clock,
            bus_clock: self.bus_clock.unwrap_or(clock),
            bitrate: self.bitrate,
            sample_point: self.sample_point,
            tolerance: self.tolerance,
            json: self.json,
            all: self.all,
        })
    }
}

/// A whole number, `_` allowed as a digit separator (`54_000_000`).
fn parse_u32(text: &str) -> Result<u32, String> {
    let digits: String = text.chars().filter(|&c| c != '_').collect();
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return Err(format!("'{text}' is not a whole number"));
    }
    digits
        .parse::<u32>()
        .map_err(|_| format!("'{text}' is too large (max {})", u32::MAX))
}

/// "87.5" or "87.5%" → 875 per mille (at most one decimal).
fn parse_percent(text: &str) -> Result<u16, String> {
    let bad = || format!("'{text}' is not a percentage like 87.5");
    let t = text.strip_suffix('%').unwrap_or(text);
    let (int, frac) = match t.split_once('.') {
        Some((i, f)) => (i, f),
        None => (t, ""),
    };
    if int.is_empty() || int.len() > 3 || !int.bytes().all(|b| b.is_ascii_digit()) {
        return Err(bad());
    }
    if frac.len() > 1 || !frac.bytes().all(|b| b.is_ascii_digit()) {
        return Err(format!(
            "'{text}': at most one decimal (per mille resolution)"
        ));
    }
    let int: u16 = int.parse().map_err(|_| bad())?;
    let frac: u16 = if frac.is_empty() {
        0
    } else {
        frac.parse().map_err(|_| bad())?
    };
    Ok(int * 10 + frac)
}

fn permille(v: u16) -> String {
    format!("{}.{}", v / 10, v % 10)
}

impl Options {
    /// The rule the driver applies (FlexCAN: Kinetis RM "Arbitration and matching
    /// timing", 16 message buffers with the Rx FIFO as the driver configures them, the
    /// bus clock given; bxCAN: the `CAN_BTR` ranges).
    fn rule(&self) -> TimingRule {
        match self.controller {
            Controller::FlexCan => flexcan_rules::rule(self.clock, self.bus_clock, 16, true),
            Controller::BxCan => TimingRule::new(self.clock, Limits::BXCAN),
        }
    }
}

/// Why the controller's manual forbids `t` beyond the register ranges, if it does
/// ([`TimingRule::manual_violation`]; bxCAN: never).
fn manual_violation(rule: &TimingRule, t: &Timing) -> Option<String> {
    rule.manual_violation(t).map(|e| e.to_string())
}

/// Register values of a timing: (name, value) pairs, the whole register first.
fn registers(t: &Timing) -> Vec<(&'static str, u32)> {
    match t.limits.controller {
        Controller::BxCan => match t.bxcan_btr_fields() {
            Ok(f) => vec![
                ("BTR", f.bits()),
                ("BRP", f.brp as u32),
                ("TS1", f.ts1 as u32),
                ("TS2", f.ts2 as u32),
                ("SJW", f.sjw as u32),
            ],
            Err(_) => vec![],
        },
        Controller::FlexCan => match t.flexcan_ctrl1_fields() {
            Ok(f) => vec![
                ("CTRL1", f.bits()),
                ("PRESDIV", f.presdiv as u32),
                ("PROPSEG", f.propseg as u32),
                ("PSEG1", f.pseg1 as u32),
                ("PSEG2", f.pseg2 as u32),
                ("RJW", f.rjw as u32),
                ("SMP", f.smp as u32),
            ],
            Err(_) => vec![],
        },
    }
}

/// The register values of a timing in JSON: the whole register (decimal and hex, plus
/// the CTRL1 timing mask for FlexCAN) first, then its fields, in that order.
struct RegistersJson {
    controller: Controller,
    values: Vec<(&'static str, u32)>,
}

impl Serialize for RegistersJson {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(None)?;
        for (i, (name, value)) in self.values.iter().enumerate() {
            map.serialize_entry(name, value)?;
            if i == 0 {
                map.serialize_entry(&format!("{name}_hex"), &format!("0x{value:08X}"))?;
                if self.controller == Controller::FlexCan {
                    map.serialize_entry(
                        &format!("{name}_mask_hex"),
                        &format!("0x{FLEXCAN_CTRL1_TIMING_MASK:08X}"),
                    )?;
                }
            }
        }
        map.end()
    }
}

/// One timing in JSON (field names are the interface: scripts read them).
#[derive(Serialize)]
struct TimingJson {
    actual_bitrate: u32,
    ppm: u64,
    exact: bool,
    ok: bool,
    sample_point_permille: u16,
    prescaler: u16,
    quanta: u32,
    tseg1: u32,
    tseg2: u32,
    prop_seg: u8,
    phase_seg1: u8,
    phase_seg2: u8,
    sjw: u8,
    triple_sampling: bool,
    oscillator_tolerance_ppm: u32,
    /// False when the controller's manual forbids the timing (`manual_rule` says why).
    manual_ok: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    manual_rule: Option<String>,
    registers: RegistersJson,
}

impl TimingJson {
    fn new(t: &Timing, tolerance: u32, rule: &TimingRule) -> Self {
        let manual_rule = manual_violation(rule, t);
        TimingJson {
            manual_ok: manual_rule.is_none(),
            manual_rule,
            actual_bitrate: t.actual_bitrate(),
            ppm: t.ppm_from_wished(),
            exact: t.is_exact(),
            ok: t.consistency().is_ok() && t.within_tolerance(tolerance),
            sample_point_permille: t.sample_point(),
            prescaler: t.prescaler,
            quanta: t.quanta(),
            tseg1: t.tseg1(),
            tseg2: t.tseg2(),
            prop_seg: t.prop_seg,
            phase_seg1: t.phase_seg1,
            phase_seg2: t.phase_seg2,
            sjw: t.sjw,
            triple_sampling: t.triple_sampling,
            oscillator_tolerance_ppm: t.oscillator_tolerance_ppm(),
            registers: RegistersJson {
                controller: t.limits.controller,
                values: registers(t),
            },
        }
    }
}

/// The whole `--json` answer: the request, the rule's range, the verdict, the chosen
/// timing, and with `--all` every timing within the tolerance.
#[derive(Serialize)]
struct Answer {
    controller: &'static str,
    clock: u32,
    bitrate: u32,
    tolerance_ppm: u32,
    sample_point_target_permille: u16,
    /// The slowest and fastest wished rates the driver accepts (the bit rates of the
    /// rule's slowest and fastest timings, rounded down).
    min_bitrate: u32,
    max_bitrate: u32,
    /// Whether the driver accepts this timing for this wished rate and tolerance.
    accepted: bool,
    /// Why not (the driver's error), when it does not.
    #[serde(skip_serializing_if = "Option::is_none")]
    refusal: Option<String>,
    #[serde(flatten)]
    chosen: TimingJson,
    #[serde(skip_serializing_if = "Option::is_none")]
    solutions: Option<Vec<TimingJson>>,
}

/// The computed answer: the target sample point, the chosen timing, the rule's verdict
/// on it ([`TimingRule::accept`]), every timing within the tolerance (with `--all`).
struct Outcome {
    rule: TimingRule,
    target: u16,
    timing: Timing,
    verdict: Result<(), TimingError>,
    all: Vec<Timing>,
}

/// Solves within the rule's limits and judges the result by the rule; `Err` (exit 2)
/// when there is no timing at all.
fn compute(o: &Options) -> Result<Outcome, String> {
    let rule = o.rule();
    let target = o.sample_point.unwrap_or(cia_sample_point(o.bitrate));
    let timing = solve(o.clock, o.bitrate, &rule.limits, target).map_err(|e| {
        format!(
            "{e} (controller {}, clock {} Hz, bit rate {} bit/s, sample point {} %)",
            o.controller.name(),
            o.clock,
            o.bitrate,
            permille(target)
        )
    })?;
    let all = if o.all {
        match Solutions::new(o.clock, o.bitrate, &rule.limits, o.tolerance) {
            Ok(s) => s.collect(),
            Err(_) => Vec::new(),
        }
    } else {
        Vec::new()
    };
    Ok(Outcome {
        verdict: rule.accept(&timing, o.tolerance),
        rule,
        target,
        timing,
        all,
    })
}

fn json(o: &Options, out: &Outcome) -> String {
    let answer = Answer {
        controller: o.controller.name(),
        clock: o.clock,
        bitrate: o.bitrate,
        tolerance_ppm: o.tolerance,
        sample_point_target_permille: out.target,
        min_bitrate: out.rule.min_bitrate(),
        max_bitrate: out.rule.max_bitrate(),
        accepted: out.verdict.is_ok(),
        refusal: out.verdict.err().map(|e| e.to_string()),
        chosen: TimingJson::new(&out.timing, o.tolerance, &out.rule),
        solutions: o.all.then(|| {
            out.all
                .iter()
                .map(|s| TimingJson::new(s, o.tolerance, &out.rule))
                .collect()
        }),
    };
    // Only strings, numbers and booleans: serialisation cannot fail.
    serde_json::to_string(&answer).unwrap_or_default()
}

fn print_text(o: &Options, out: &Outcome) {
    let (target, t, all) = (out.target, &out.timing, &out.all);
    let ok = t.within_tolerance(o.tolerance);
    println!("controller      {}", o.controller.name());
    println!("clock           {} Hz", o.clock);
    println!("wished rate     {} bit/s", o.bitrate);
    println!(
        "actual rate     {} bit/s{}",
        t.actual_bitrate(),
        if t.is_exact() { " (exact)" } else { "" }
    );
    println!(
        "error           {} ppm (tolerance {} ppm): {}",
        t.ppm_from_wished(),
        o.tolerance,
        if ok {
            "ok"
        } else {
            "TOO FAR from wished bit rate"
        }
    );
    println!("prescaler       {}", t.prescaler);
    match o.controller {
        Controller::FlexCan => println!(
            "quanta per bit  {} = 1 + tseg1 {} (PROPSEG {} + PSEG1 {}) + tseg2 {} (PSEG2)",
            t.quanta(),
            t.tseg1(),
            t.prop_seg,
            t.phase_seg1,
            t.tseg2()
        ),
        Controller::BxCan => println!(
            "quanta per bit  {} = 1 + tseg1 {} (TS1) + tseg2 {} (TS2)",
            t.quanta(),
            t.tseg1(),
            t.tseg2()
        ),
    }
    println!(
        "sample point    {} % (target {} %)",
        permille(t.sample_point()),
        permille(target)
    );
    println!("sjw             {}", t.sjw);
    if o.controller == Controller::FlexCan {
        match manual_violation(&out.rule, t) {
            None => println!(
                "Kinetis RM      ok (8+ quanta, 16+ bus clocks per bit at bus {} Hz)",
                o.bus_clock
            ),
            Some(why) => println!("Kinetis RM      FORBIDDEN: {why}"),
        }
    }
    println!("osc. tolerance  {} ppm", t.oscillator_tolerance_ppm());
    println!(
        "accepted range  {} ..= {} bit/s",
        out.rule.min_bitrate(),
        out.rule.max_bitrate()
    );
    match out.verdict {
        Ok(()) => println!("driver          accepts"),
        Err(e) => println!("driver          REFUSES: {e}"),
    }
    let regs = registers(t);
    if let Some(((name, value), fields)) = regs.split_first() {
        match o.controller {
            Controller::FlexCan => println!(
                "{name} (timing)  0x{value:08X}  (write (CTRL1 & !0x{FLEXCAN_CTRL1_TIMING_MASK:08X}) | 0x{value:08X})"
            ),
            Controller::BxCan => {
                println!("{name}             0x{value:08X}  (LBKM/SILM mode bits clear)")
            }
        }
        let fields: Vec<String> = fields.iter().map(|(n, v)| format!("{n} = {v}")).collect();
        println!("  fields        {}", fields.join(", "));
    }
    if o.all {
        println!();
        println!(
            "{} timing(s) within {} ppm (* = chosen):",
            all.len(),
            o.tolerance
        );
        println!("    prescaler quanta tseg1 tseg2 sjw sample%  actual      ppm  register");
        for s in all {
            let reg = registers(s).first().map(|r| r.1).unwrap_or(0);
            println!(
                "  {} {:>9} {:>6} {:>5} {:>5} {:>3} {:>7} {:>7} {:>8}  0x{reg:08X}",
                if s == t { '*' } else { ' ' },
                s.prescaler,
                s.quanta(),
                s.tseg1(),
                s.tseg2(),
                s.sjw,
                permille(s.sample_point()),
                s.actual_bitrate(),
                s.ppm_from_wished(),
            );
        }
    }
}

fn main() -> ExitCode {
    // Bad options: clap prints the error with a usage line and exits with status 2.
    let o = match Args::parse().options() {
        Ok(o) => o,
        Err(e) => e.exit(),
    };
    let out = match compute(&o) {
        Ok(out) => out,
        Err(e) => {
            eprintln!("can-timing: error: {e}");
            return ExitCode::from(2);
        }
    };
    if o.json {
        println!("{}", json(&o, &out));
    } else {
        print_text(&o, &out);
    }
    if out.verdict.is_ok() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_args(line: &str) -> Result<Options, clap::Error> {
        let argv = std::iter::once("can-timing").chain(line.split_whitespace());
        Args::try_parse_from(argv)?.options()
    }

    fn run_json(line: &str) -> String {
        let o = parse_args(line).unwrap();
        json(&o, &compute(&o).unwrap())
    }

    #[test]
    fn json_output() {
        let j = run_json("--controller bxcan --clock 54000000 --bitrate 500000 --json");
        for field in [
            "\"bitrate\":500000,",
            "\"actual_bitrate\":500000,",
            "\"ppm\":0,",
            "\"sample_point_permille\":888,",
            "\"prescaler\":6,",
            "\"tseg1\":15,",
            "\"tseg2\":2,",
            "\"sjw\":2,",
            "\"ok\":true,",
            "\"BTR_hex\":\"0x011E0005\"",
        ] {
            assert!(j.contains(field), "{field} in {j}");
        }
        assert!(j.starts_with('{') && j.ends_with('}') && !j.contains('\n'));
        let j = run_json("--controller flexcan --bitrate 842000 --json");
        assert!(j.contains("\"actual_bitrate\":842105,") && j.contains("\"ppm\":124,"));
        let j = run_json("--controller flexcan --bitrate 440000 --tolerance 0 --json --all");
        assert!(j.contains("\"ok\":false,") && j.contains("\"solutions\":[]"));
        let j = run_json("--controller flexcan --bitrate 500000 --tolerance 0 --json --all");
        assert_eq!(j.matches("\"prescaler\":").count(), 1 + 11);
        // Balanced braces and brackets.
        assert_eq!(j.matches('{').count(), j.matches('}').count());
        assert_eq!(j.matches('[').count(), j.matches(']').count());
    }

    #[test]
    fn flexcan_manual_rules() {
        // 1 Mbit/s from 16 MHz: 16 quanta, 16 bus clocks per bit at the default bus
        // clock (the CAN clock): the edge, allowed.
        let j = run_json("--controller flexcan --bitrate 1000000 --json");
        assert!(
            j.contains("\"manual_ok\":true,") && !j.contains("manual_rule"),
            "{j}"
        );
        // 2 Mbit/s: 8 quanta, but 8 bus clocks per bit from a 16 MHz bus.
        let j = run_json("--controller flexcan --bitrate 2000000 --json");
        assert!(j.contains("\"manual_ok\":false,"), "{j}");
        assert!(j.contains("8 peripheral clocks per CAN bit"), "{j}");
        let j = run_json("--controller flexcan --bitrate 2000000 --bus-clock 32000000 --json");
        assert!(j.contains("\"manual_ok\":true,"), "{j}");
        // ACAN's 3.2 Mbit/s is 5 quanta: no timing of 8 or more, whatever the bus
        // clock (exit status 2, as the driver has none either).
        let o = parse_args("--controller flexcan --bitrate 3200000 --bus-clock 60000000").unwrap();
        assert!(compute(&o).err().unwrap().contains("above"));
        // A bus clock below the CAN clock.
        let j = run_json("--controller flexcan --bitrate 125000 --bus-clock 8000000 --json");
        assert!(j.contains("below the CAN clock"), "{j}");
        // bxCAN has no such rule.
        let j = run_json("--controller bxcan --clock 54000000 --bitrate 1000000 --json");
        assert!(j.contains("\"manual_ok\":true,"), "{j}");
        let o = parse_args("--controller flexcan --bitrate 1000000").unwrap();
        assert_eq!(o.bus_clock, 16_000_000);
    }

    /// Issue 22: the tool judges by the driver's rule, one bit per second beyond the
    /// fastest and the slowest accepted rates is refused, the rates themselves accepted.
    #[test]
    fn the_driver_s_rule_decides() {
        let verdict = |line: &str| compute(&parse_args(line).unwrap()).unwrap().verdict;
        assert_eq!(verdict("--controller flexcan --bitrate 1000000"), Ok(()));
        assert_eq!(
            verdict("--controller flexcan --bitrate 1000001"),
            Err(TimingError::BitrateTooHigh)
        );
        assert_eq!(verdict("--controller flexcan --bitrate 2500"), Ok(()));
        assert_eq!(
            verdict("--controller flexcan --bitrate 2499"),
            Err(TimingError::BitrateTooLow)
        );
        assert_eq!(
            verdict("--controller flexcan --bitrate 2000000 --bus-clock 16000000"),
            Err(TimingError::BitrateTooHigh)
        );
        assert_eq!(
            verdict("--controller bxcan --clock 54000000 --bitrate 2109"),
            Ok(())
        );
        assert_eq!(
            verdict("--controller bxcan --clock 54000000 --bitrate 2108"),
            Err(TimingError::BitrateTooLow)
        );
        assert_eq!(
            verdict("--controller bxcan --clock 54000000 --bitrate 18000000"),
            Ok(())
        );
        // Above 54 MHz / 3 quanta there is no timing at all (exit status 2).
        let o = parse_args("--controller bxcan --clock 54000000 --bitrate 18000001").unwrap();
        assert!(compute(&o).is_err());
        let j = run_json("--controller bxcan --clock 54000000 --bitrate 2108 --json");
        let v: serde_json::Value = serde_json::from_str(&j).unwrap();
        assert_eq!(v["accepted"], false);
        assert_eq!(
            (v["min_bitrate"].as_u64(), v["max_bitrate"].as_u64()),
            (Some(2_109), Some(18_000_000))
        );
        assert!(v["refusal"].as_str().unwrap().contains("below"), "{j}");
        // The timings it accepts are the driver's: 8 quanta at least on FlexCAN.
        let o = parse_args("--controller flexcan --bitrate 15166 --all").unwrap();
        let out = compute(&o).unwrap();
        assert_eq!(out.verdict, Ok(()));
        assert!(out.timing.quanta() >= 8 && out.all.iter().all(|t| t.quanta() >= 8));
    }

    #[test]
    fn percent_parsing() {
        assert_eq!(parse_percent("87.5"), Ok(875));
        assert_eq!(parse_percent("80"), Ok(800));
        assert_eq!(parse_percent("75%"), Ok(750));
        assert!(parse_percent("87.55").is_err());
        assert!(parse_percent("x").is_err());
        assert!(parse_percent("").is_err());
        assert!(parse_percent("-5").is_err());
    }

    #[test]
    fn option_parsing() {
        let o = parse_args("--controller flexcan --bitrate 842000").unwrap();
        assert_eq!(o.clock, 16_000_000);
        assert_eq!(o.tolerance, 1000);
        let o =
            parse_args("--controller=bxcan --clock=54_000_000 --bitrate 500000 --json").unwrap();
        assert_eq!((o.clock, o.json, o.bitrate), (54_000_000, true, 500_000));
        // `--x=v` and `--x v` alike, controller names in any case.
        let o =
            parse_args("--controller BxCAN --clock 8000000 --bitrate=250000 --sample-point=75%")
                .unwrap();
        assert_eq!(
            (o.controller, o.clock, o.bitrate, o.sample_point),
            (Controller::BxCan, 8_000_000, 250_000, Some(750))
        );
        let kind = |line: &str| parse_args(line).err().map(|e| e.kind());
        assert_eq!(
            kind("--controller bxcan --bitrate 500000"),
            Some(ErrorKind::MissingRequiredArgument)
        );
        assert_eq!(
            kind("--controller can --bitrate 5"),
            Some(ErrorKind::InvalidValue)
        );
        assert_eq!(
            kind("--controller flexcan"),
            Some(ErrorKind::MissingRequiredArgument)
        );
        assert_eq!(
            kind("--controller flexcan --bitrate"),
            Some(ErrorKind::InvalidValue)
        );
        assert_eq!(
            kind("--controller flexcan --bitrate 99999999999"),
            Some(ErrorKind::ValueValidation)
        );
        assert_eq!(
            kind("--controller flexcan --bitrate 1 --frob"),
            Some(ErrorKind::UnknownArgument)
        );
        assert_eq!(
            kind("--controller flexcan --bitrate 1 --json=yes"),
            Some(ErrorKind::TooManyValues)
        );
        assert_eq!(kind("--help"), Some(ErrorKind::DisplayHelp));
        // Every bad input exits with status 2 (clap's usage-error status).
        let e = parse_args("--controller flexcan --bitrate x")
            .err()
            .unwrap();
        assert_eq!(e.exit_code(), 2);
        Args::command().debug_assert();
    }

    #[test]
    fn json_is_valid_and_ordered() {
        let j = run_json("--controller flexcan --bitrate 500000 --json --all");
        let v: serde_json::Value = serde_json::from_str(&j).unwrap();
        assert_eq!(v["controller"], "flexcan");
        assert_eq!(v["clock"], 16_000_000);
        assert_eq!(v["registers"]["CTRL1_mask_hex"], "0xFFFF0087");
        assert!(v["solutions"].as_array().is_some_and(|s| !s.is_empty()));
        // The register comes before its fields, as before.
        let at = |k: &str| j.find(k).unwrap();
        assert!(at("\"CTRL1\"") < at("\"CTRL1_hex\"") && at("\"CTRL1_hex\"") < at("\"PRESDIV\""));
        assert!(
            at("\"controller\"") < at("\"actual_bitrate\"")
                && at("\"registers\"") < at("\"solutions\"")
        );
    }
}
