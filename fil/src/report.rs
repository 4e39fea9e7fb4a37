//! The per-board report `can-fil` prints.

use std::fmt::Write;

use crate::machine::{exception_name, unknown_report};
use crate::world::World;

/// The report of a run.
pub fn render(world: &World<'_>) -> String {
    let mut out = String::new();
    let secs = world.now_ps as f64 / 1e12;
    let _ = writeln!(
        out,
        "bus: {} bit/s, {:.3} s simulated, {} frame attempts, {} error-free",
        world.bus.bit_rate(),
        secs,
        world.bus.stats().frames_started,
        world.bus.stats().frames_error_free
    );
    for (i, m) in world.machines.iter().enumerate() {
        let b = m.board();
        let _ = writeln!(out, "\n[{}] {}", b.name, m.image.path);
        let _ = writeln!(
            out,
            "  instructions: {}  (core {} Hz now, {} cycles asleep)",
            b.instructions,
            b.profile.core_hz(),
            b.idle_cycles
        );
        let at = m
            .image
            .function_at(b.last_pc())
            .map_or(String::new(), |s| format!(" in {}", s.name));
        let _ = writeln!(out, "  last instruction: 0x{:08X}{at}", b.last_pc());
        let mut lines = Vec::new();
        for (e, n) in &b.taken {
            let mut name = exception_name(*e);
            if *e >= 16 {
                for port in &b.cans {
                    for (line, irq) in &port.instance.irqs {
                        if irq + 16 == *e {
                            name = format!("{name} ({} {line})", port.instance.name);
                        }
                    }
                }
            }
            lines.push(format!("{name}: {n}"));
        }
        let _ = writeln!(
            out,
            "  interrupts taken: {}",
            if lines.is_empty() {
                "none".into()
            } else {
                lines.join(", ")
            }
        );
        for a in world.attached.iter().filter(|a| a.board == i) {
            let s = world.bus.node_stats(a.node).unwrap_or_default();
            let (tec, rec) = b.cans[a.port].model.counters();
            let rate = a
                .bit_rate
                .map_or("not on the bus".to_string(), |r| format!("{r} bit/s"));
            let _ = writeln!(
                out,
                "  {}: sent {} (+{} internal), received {}, tx errors {}, rx errors {}, TEC {tec} REC {rec}, {rate}{}",
                a.name, s.sent, s.sent_internal, s.received, s.tx_errors, s.rx_errors,
                if a.misclocked { " (OUT OF TOLERANCE)" } else { "" }
            );
        }
        if let (Some(s), Some(whole)) = (&b.stack, m.stack_high_water()) {
            let config = match s.configuration {
                Some((bytes, at_ns)) => format!(
                    "configuration {bytes} B (until the last CAN controller started had a line unmasked, at {} us)",
                    at_ns / 1000
                ),
                None => "configuration not reached (no CAN interrupt line unmasked)".into(),
            };
            let _ = writeln!(
                out,
                "  stack: {config}, whole run {whole} B, painted {} B from 0x{:08X}{}",
                s.painted(),
                s.bottom,
                if whole >= s.painted() {
                    " (ALL OF IT: overflow?)"
                } else {
                    ""
                }
            );
        }
        if b.faults.is_empty() {
            let _ = writeln!(out, "  faults: none");
        }
        for f in &b.faults {
            let _ = writeln!(out, "  FAULT: {f}");
        }
        for s in &b.stuck {
            let _ = writeln!(
                out,
                "  STUCK INTERRUPT: {} entered {} times in a row with no thread progress (line stays asserted; t = {} us)",
                exception_name(s.exception),
                crate::machine::STUCK_ENTRIES,
                s.at_ns / 1000
            );
        }
        if let Some(l) = &b.livelock {
            let _ = writeln!(out, "  LIVELOCK: {l}");
        }
        if let Some(h) = &b.halted {
            let _ = writeln!(out, "  HALTED: {h}");
        }
        for u in unknown_report(b) {
            let _ = writeln!(out, "  unknown register: {u}");
        }
        for f in &b.findings {
            let _ = writeln!(out, "  finding: {f}");
        }
        if let Some(rtt) = &b.rtt {
            let lines = m.defmt_lines();
            let _ = writeln!(out, "  defmt log ({} lines):", lines.len());
            for l in &lines {
                let _ = writeln!(out, "    | {l}");
            }
            if let Some(e) = &rtt.error {
                let _ = writeln!(out, "  RTT: {e}");
            }
        }
        if !b.console.is_empty() {
            let _ = writeln!(out, "  console:");
            for l in b.console.lines() {
                let _ = writeln!(out, "    | {l}");
            }
        }
    }
    for n in &world.nodes {
        let s = world.bus.node_stats(n.node).unwrap_or_default();
        let c = n.sim.borrow().counters();
        let _ = writeln!(
            out,
            "\n[{}] plain node, {} bit/s{}: sent {}, received {}, tx errors {}, rx errors {}, TEC {} REC {}",
            n.name, n.bit_rate, if n.misclocked { " (OUT OF TOLERANCE)" } else { "" },
            s.sent, s.received, s.tx_errors, s.rx_errors, c.tec, c.rec
        );
    }
    for c in &world.changes {
        let _ = writeln!(
            out,
            "error state: {} {} -> {} at {} us",
            c.node, c.from, c.to, c.at_us
        );
    }
    out
}
