//! `can-timing`: CAN bit timing calculator for FlexCAN and bxCAN.
//!
//! ```text
//! can-timing --controller flexcan|bxcan [--clock HZ] --bitrate BPS
//!            [--sample-point PCT] [--tolerance PPM] [--json] [--all]
//! ```
//!
//! Exit status: 0 timing found within tolerance, 1 timing printed but outside the
//! tolerance (ACAN "too far from wished bit rate"), 2 bad options or input.

use std::fmt::Write as _;
use std::process::ExitCode;

use twocan_core::timing::{
    cia_sample_point, solve, Controller, Limits, Solutions, Timing, DEFAULT_TOLERANCE_PPM,
    FLEXCAN_CTRL1_TIMING_MASK,
};

const USAGE: &str = "\
usage: can-timing --controller flexcan|bxcan [--clock HZ] --bitrate BPS
                  [--sample-point PCT] [--tolerance PPM] [--json] [--all]

  --controller     flexcan (NXP FlexCAN, CTRL1) or bxcan (STM32 bxCAN, CAN_BTR)
  --clock HZ       CAN clock in Hz (flexcan default 16000000, ACAN's CAN clock;
                   bxcan: required, the APB1 clock, e.g. 54000000)
  --bitrate BPS    wished bit rate in bit/s
  --sample-point   target sample point in per cent, e.g. 87.5 (default: CiA,
                   87.5 up to 500 kbit/s, 80 up to 800 kbit/s, 75 above)
  --tolerance PPM  accepted distance from the wished bit rate (default 1000,
                   0 = exact only)
  --json           print one JSON object
  --all            also list every timing within the tolerance
  -h, --help       this text

exit status: 0 ok, 1 outside tolerance, 2 bad options";

struct Options {
    controller: Controller,
    clock: u32,
    bitrate: u32,
    sample_point: Option<u16>,
    tolerance: u32,
    json: bool,
    all: bool,
}

fn parse_u32(name: &str, text: &str) -> Result<u32, String> {
    let digits: String = text.chars().filter(|&c| c != '_').collect();
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return Err(format!("{name}: '{text}' is not a whole number"));
    }
    digits
        .parse::<u32>()
        .map_err(|_| format!("{name}: '{text}' is too large (max {})", u32::MAX))
}

/// "87.5" or "87.5%" → 875 per mille (at most one decimal).
fn parse_percent(text: &str) -> Result<u16, String> {
    let bad = || format!("--sample-point: '{text}' is not a percentage like 87.5");
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
            "--sample-point: '{text}': at most one decimal (per mille resolution)"
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

fn parse_args(args: &[String]) -> Result<Option<Options>, String> {
    let mut controller = None;
    let mut clock = None;
    let mut bitrate = None;
    let mut sample_point = None;
    let mut tolerance = DEFAULT_TOLERANCE_PPM;
    let mut json = false;
    let mut all = false;
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let (name, inline) = match arg.split_once('=') {
            Some((n, v)) if n.starts_with("--") => (n, Some(v.to_string())),
            _ => (arg.as_str(), None),
        };
        let mut value = || -> Result<String, String> {
            match inline.clone() {
                Some(v) => Ok(v),
                None => it
                    .next()
                    .cloned()
                    .ok_or_else(|| format!("{name} needs a value")),
            }
        };
        match name {
            "-h" | "--help" => return Ok(None),
            "--controller" => {
                controller = Some(match value()?.to_ascii_lowercase().as_str() {
                    "flexcan" => Controller::FlexCan,
                    "bxcan" => Controller::BxCan,
                    other => {
                        return Err(format!(
                            "--controller: unknown controller '{other}' (flexcan or bxcan)"
                        ))
                    }
                })
            }
            "--clock" => clock = Some(parse_u32(name, &value()?)?),
            "--bitrate" => bitrate = Some(parse_u32(name, &value()?)?),
            "--sample-point" => sample_point = Some(parse_percent(&value()?)?),
            "--tolerance" => tolerance = parse_u32(name, &value()?)?,
            "--json" | "--all" if inline.is_some() => return Err(format!("{name} takes no value")),
            "--json" => json = true,
            "--all" => all = true,
            other => return Err(format!("unknown option '{other}'")),
        }
    }
    let controller = controller.ok_or("--controller is required (flexcan or bxcan)")?;
    let clock = match (clock, controller) {
        (Some(c), _) => c,
        (None, Controller::FlexCan) => 16_000_000,
        (None, Controller::BxCan) => {
            return Err("--clock is required for bxcan (the APB1 clock in Hz)".into())
        }
    };
    let bitrate = bitrate.ok_or("--bitrate is required")?;
    Ok(Some(Options {
        controller,
        clock,
        bitrate,
        sample_point,
        tolerance,
        json,
        all,
    }))
}

fn permille(v: u16) -> String {
    format!("{}.{}", v / 10, v % 10)
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

fn json_timing(out: &mut String, t: &Timing, tolerance: u32) {
    let ok = t.consistency().is_ok() && t.within_tolerance(tolerance);
    let _ = write!(
        out,
        "\"actual_bitrate\":{},\"ppm\":{},\"exact\":{},\"ok\":{},\"sample_point_permille\":{},\
         \"prescaler\":{},\"quanta\":{},\"tseg1\":{},\"tseg2\":{},\"prop_seg\":{},\
         \"phase_seg1\":{},\"phase_seg2\":{},\"sjw\":{},\"triple_sampling\":{},\
         \"oscillator_tolerance_ppm\":{},\"registers\":{{",
        t.actual_bitrate(),
        t.ppm_from_wished(),
        t.is_exact(),
        ok,
        t.sample_point(),
        t.prescaler,
        t.quanta(),
        t.tseg1(),
        t.tseg2(),
        t.prop_seg,
        t.phase_seg1,
        t.phase_seg2,
        t.sjw,
        t.triple_sampling,
        t.oscillator_tolerance_ppm(),
    );
    for (i, (name, value)) in registers(t).iter().enumerate() {
        if i == 0 {
            let _ = write!(out, "\"{name}\":{value},\"{name}_hex\":\"0x{value:08X}\"");
            if t.limits.controller == Controller::FlexCan {
                let _ = write!(
                    out,
                    ",\"{name}_mask_hex\":\"0x{FLEXCAN_CTRL1_TIMING_MASK:08X}\""
                );
            }
        } else {
            let _ = write!(out, ",\"{name}\":{value}");
        }
    }
    out.push('}');
}

fn json(o: &Options, target: u16, t: &Timing, all: &[Timing]) -> String {
    let mut out = String::new();
    let _ = write!(
        out,
        "{{\"controller\":\"{}\",\"clock\":{},\"bitrate\":{},\"tolerance_ppm\":{},\
         \"sample_point_target_permille\":{},",
        o.controller.name(),
        o.clock,
        o.bitrate,
        o.tolerance,
        target
    );
    json_timing(&mut out, t, o.tolerance);
    if o.all {
        out.push_str(",\"solutions\":[");
        for (i, s) in all.iter().enumerate() {
            if i > 0 {
                out.push(',');
            }
            out.push('{');
            json_timing(&mut out, s, o.tolerance);
            out.push('}');
        }
        out.push(']');
    }
    out.push('}');
    out
}

fn print_text(o: &Options, target: u16, t: &Timing, all: &[Timing]) {
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
    println!("osc. tolerance  {} ppm", t.oscillator_tolerance_ppm());
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
    let args: Vec<String> = std::env::args().skip(1).collect();
    let o = match parse_args(&args) {
        Ok(Some(o)) => o,
        Ok(None) => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        Err(msg) => {
            eprintln!("can-timing: error: {msg}\n(see can-timing --help)");
            return ExitCode::from(2);
        }
    };
    let limits: Limits = o.controller.limits();
    let target = o.sample_point.unwrap_or(cia_sample_point(o.bitrate));
    let t = match solve(o.clock, o.bitrate, &limits, target) {
        Ok(t) => t,
        Err(e) => {
            eprintln!(
                "can-timing: error: {e} (controller {}, clock {} Hz, bit rate {} bit/s, sample point {} %)",
                o.controller.name(),
                o.clock,
                o.bitrate,
                permille(target)
            );
            return ExitCode::from(2);
        }
    };
    let all: Vec<Timing> = if o.all {
        match Solutions::new(o.clock, o.bitrate, &limits, o.tolerance) {
            Ok(s) => s.collect(),
            Err(_) => Vec::new(),
        }
    } else {
        Vec::new()
    };
    if o.json {
        println!("{}", json(&o, target, &t, &all));
    } else {
        print_text(&o, target, &t, &all);
    }
    if t.validate(o.tolerance).is_ok() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    fn run_json(line: &str) -> String {
        let o = parse_args(&args(line)).unwrap().unwrap();
        let limits = o.controller.limits();
        let target = o.sample_point.unwrap_or(cia_sample_point(o.bitrate));
        let t = solve(o.clock, o.bitrate, &limits, target).unwrap();
        let all: Vec<Timing> = Solutions::new(o.clock, o.bitrate, &limits, o.tolerance)
            .unwrap()
            .collect();
        json(&o, target, &t, &all)
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
        let o = parse_args(&args("--controller flexcan --bitrate 842000"))
            .unwrap()
            .unwrap();
        assert_eq!(o.clock, 16_000_000);
        assert_eq!(o.tolerance, 1000);
        let o = parse_args(&args(
            "--controller=bxcan --clock=54_000_000 --bitrate 500000 --json",
        ))
        .unwrap()
        .unwrap();
        assert_eq!((o.clock, o.json), (54_000_000, true));
        assert!(parse_args(&args("--controller bxcan --bitrate 500000")).is_err());
        assert!(parse_args(&args("--controller can --bitrate 5")).is_err());
        assert!(parse_args(&args("--controller flexcan")).is_err());
        assert!(parse_args(&args("--controller flexcan --bitrate")).is_err());
        assert!(parse_args(&args("--controller flexcan --bitrate 99999999999")).is_err());
        assert!(parse_args(&args("--controller flexcan --bitrate 1 --frob")).is_err());
        assert!(parse_args(&args("--help")).unwrap().is_none());
    }
}
