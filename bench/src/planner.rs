//! Filter-planner quality on a corpus of real message-identifier sets
//! (`bench/data/dbc_ids.txt`: the identifiers of public vehicle DBC files).
//!
//! For every set (all data frames, one exact filter per identifier):
//!
//! - **bxCAN** (28 banks): banks of the list-only plan (`merge(false)`), of the merged
//!   plan, and the exact lower bound: `⌈q / 4⌉` where `q` is the weight in quarter banks
//!   of a minimum-weight cover of the set by exact cubes (standard single 1, standard
//!   block 2, extended single 2, extended block 4), computed here by exhaustive search
//!   (all exact cubes of four or more identifiers, branch and bound per connected
//!   component); sets that fit no plan are planned in superset mode, with the number of
//!   extra identifiers the hardware accepts;
//! - **FlexCAN**: for each configuration (8/0, 10/6, 12/12, 14/18) how many sets fit
//!   exactly with one element per identifier and with merging, and the superset extras
//!   of the rest.
//!
//! Entry point: [`report`] (a Markdown section).

use std::collections::{HashMap, HashSet};

use twocan_bxcan::filters::MAX_LOOKUP_KEYS;
use twocan_bxcan::{PlanError, PlanOptions};
use twocan_core::Filter;
use twocan_flexcan::planner::{self as flex, PlanOptions as FlexOptions};
use twocan_flexcan::Configuration;

/// The planners' quality is measured unconstrained by a driver's lookup capacity (room
/// for every key; a driver with the default capacity gets plans that need fewer keys,
/// `docs/filters.md`).
type FilterPlan = twocan_bxcan::FilterPlan<MAX_LOOKUP_KEYS>;

fn plan(filters: &[Filter], options: PlanOptions) -> Result<FilterPlan, PlanError> {
    twocan_bxcan::planner::plan_for::<MAX_LOOKUP_KEYS>(filters, options)
}

fn flex_plan(
    filters: &[Filter],
    options: FlexOptions,
) -> Result<twocan_flexcan::FilterTable<MAX_LOOKUP_KEYS>, flex::PlanError> {
    flex::plan_for::<MAX_LOOKUP_KEYS>(filters, options)
}

/// The corpus, shipped in the repository.
pub const CORPUS: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/dbc_ids.txt"));

/// One identifier set of the corpus.
#[derive(Debug, Clone)]
pub struct IdSet {
    /// The DBC file it comes from.
    pub name: String,
    /// Standard identifiers.
    pub standard: Vec<u32>,
    /// Extended identifiers.
    pub extended: Vec<u32>,
}

impl IdSet {
    /// One data-frame filter per identifier, standard first.
    pub fn filters(&self) -> Vec<Filter> {
        self.standard
            .iter()
            .map(|&i| Filter::standard(i as u16))
            .chain(self.extended.iter().map(|&i| Filter::extended(i)))
            .collect()
    }

    /// Number of identifiers.
    pub fn len(&self) -> usize {
        self.standard.len() + self.extended.len()
    }
}

/// Parses the corpus format (`NAME: ID ID ...`, hexadecimal, `x` prefix for extended).
pub fn parse(text: &str) -> Result<Vec<IdSet>, String> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (name, ids) = line
            .split_once(':')
            .ok_or_else(|| format!("line {}: no `:`", n + 1))?;
        let mut set = IdSet {
            name: name.trim().to_string(),
            standard: Vec::new(),
            extended: Vec::new(),
        };
        for word in ids.split_whitespace() {
            let (ext, hex) = match word.strip_prefix('x') {
                Some(h) => (true, h),
                None => (false, word),
            };
            let id = u32::from_str_radix(hex, 16)
                .map_err(|e| format!("line {}: `{word}`: {e}", n + 1))?;
            match (ext, id) {
                (false, 0..=0x7FF) => set.standard.push(id),
                (true, 0..=0x1FFF_FFFF) => set.extended.push(id),
                _ => return Err(format!("line {}: `{word}` out of range", n + 1)),
            }
        }
        out.push(set);
    }
    Ok(out)
}

/// Every exact cube of at least four identifiers of `ids` that no larger exact cube
/// contains (maximal cubes; a cover may always use maximal ones at the same weight).
fn maximal_blocks(ids: &[u32], bits: u32) -> Vec<(u32, u32)> {
    let set: HashSet<u32> = ids.iter().copied().collect();
    // Level by level: cubes (base, dc) of size 2^level.
    let mut level: HashSet<(u32, u32)> = ids.iter().map(|&i| (i, 0)).collect();
    let mut all: Vec<HashSet<(u32, u32)>> = Vec::new();
    while !level.is_empty() {
        let mut next = HashSet::new();
        for &(base, dc) in &level {
            for b in 0..bits {
                let bit = 1 << b;
                if dc & bit != 0 || base & bit != 0 {
                    continue;
                }
                if level.contains(&(base | bit, dc)) {
                    next.insert((base, dc | bit));
                }
            }
        }
        all.push(level);
        level = next;
    }
    let _ = set;
    let mut out = Vec::new();
    for (size_log, cubes) in all.iter().enumerate() {
        if size_log < 2 {
            continue;
        }
        for &(base, dc) in cubes {
            // Maximal: no cube of the next level contains it.
            let bigger = all.get(size_log + 1).is_some_and(|up| {
                (0..bits).any(|b| {
                    let bit = 1 << b;
                    dc & bit == 0 && up.contains(&(base & !bit, dc | bit))
                })
            });
            if !bigger {
                out.push((base, dc));
            }
        }
    }
    out
}

/// Minimum cover weight of `ids` in units of a single entry (a block costs 2), and
/// whether the search finished within its budget (otherwise a lower bound).
fn min_cover(ids: &[u32], bits: u32) -> (u64, bool) {
    let blocks = maximal_blocks(ids, bits);
    let index: HashMap<u32, usize> = ids.iter().enumerate().map(|(i, &k)| (k, i)).collect();
    let members: Vec<Vec<usize>> = blocks
        .iter()
        .map(|&(base, dc)| {
            ids.iter()
                .filter(|&&k| k & !dc == base)
                .map(|k| index[k])
                .collect()
        })
        .collect();
    let mut of_key: Vec<Vec<usize>> = vec![Vec::new(); ids.len()];
    for (b, m) in members.iter().enumerate() {
        for &k in m {
            of_key[k].push(b);
        }
    }
    // Each key's cheapest share: 1 alone, 2/size in its largest block.
    let share: Vec<f64> = (0..ids.len())
        .map(|k| {
            of_key[k]
                .iter()
                .map(|&b| 2.0 / members[b].len() as f64)
                .fold(1.0, f64::min)
        })
        .collect();
    struct Search<'a> {
        members: &'a [Vec<usize>],
        of_key: &'a [Vec<usize>],
        share: &'a [f64],
        covered: Vec<bool>,
        best: u64,
        nodes: u64,
    }
    const BUDGET: u64 = 2_000_000;
    impl Search<'_> {
        fn go(&mut self, cost: u64) {
            self.nodes += 1;
            if self.nodes > BUDGET {
                return;
            }
            let bound: f64 = (0..self.covered.len())
                .filter(|&k| !self.covered[k])
                .map(|k| self.share[k])
                .sum();
            if cost as f64 + bound - 1e-9 >= self.best as f64 {
                return;
            }
            // The uncovered key with the fewest blocks.
            let Some(k) = (0..self.covered.len())
                .filter(|&k| !self.covered[k])
                .min_by_key(|&k| self.of_key[k].len())
            else {
                self.best = cost;
                return;
            };
            for b in self.of_key[k].clone() {
                let newly: Vec<usize> = self.members[b]
                    .iter()
                    .copied()
                    .filter(|&x| !self.covered[x])
                    .collect();
                for &x in &newly {
                    self.covered[x] = true;
                }
                self.go(cost + 2);
                for &x in &newly {
                    self.covered[x] = false;
                }
            }
            self.covered[k] = true;
            self.go(cost + 1);
            self.covered[k] = false;
        }
    }
    let mut s = Search {
        members: &members,
        of_key: &of_key,
        share: &share,
        covered: vec![false; ids.len()],
        best: ids.len() as u64,
        nodes: 0,
    };
    s.go(0);
    if s.nodes > BUDGET {
        let bound: f64 = share.iter().sum();
        (bound.ceil() as u64, false)
    } else {
        (s.best, true)
    }
}

/// The exact lower bound of a set's banks: `⌈quarters / 4⌉` of a minimum-weight cover,
/// and whether it is exact (search finished).
pub fn bank_bound(set: &IdSet) -> (u64, bool) {
    let (s, s_exact) = min_cover(&set.standard, 11);
    let (e, e_exact) = min_cover(&set.extended, 29);
    ((s + 2 * e).div_ceil(4), s_exact && e_exact)
}

/// bxCAN result of one set.
#[derive(Debug, Clone)]
pub struct BxRow {
    /// The set's name.
    pub name: String,
    /// Identifiers.
    pub ids: usize,
    /// Banks of the list-only plan (needed, when above 28).
    pub list_only: u64,
    /// Banks of the merged plan (needed, when above 28).
    pub merged: u64,
    /// Exact lower bound and whether the cover search finished.
    pub bound: (u64, bool),
    /// Superset extra identifiers when the exact plan does not fit 28 banks.
    pub superset_extra: Option<u64>,
}

fn banks(r: Result<FilterPlan, PlanError>) -> u64 {
    match r {
        Ok(p) => p.bank_count() as u64,
        Err(PlanError::TooManyBanks { needed, .. }) => needed as u64,
        Err(e) => panic!("{e:?}"),
    }
}

/// Plans every set for bxCAN.
pub fn bxcan_rows(sets: &[IdSet]) -> Vec<BxRow> {
    sets.iter()
        .map(|set| {
            let f = set.filters();
            let all = PlanOptions::new(28).merge(true);
            let merged = banks(plan(&f, all));
            let superset_extra = (merged > 28).then(|| {
                plan(&f, all.superset(true))
                    .map(|p| p.superset_extra())
                    .unwrap_or(u64::MAX)
            });
            BxRow {
                name: set.name.clone(),
                ids: set.len(),
                list_only: banks(plan(&f, all.merge(false))),
                merged,
                bound: bank_bound(set),
                superset_extra,
            }
        })
        .collect()
}

/// FlexCAN results per configuration: (sets fitting with one element per identifier,
/// sets fitting merged, superset extras of the others (sum, worst)).
pub fn flexcan_rows(sets: &[IdSet]) -> Vec<(Configuration, usize, usize, u64, u64)> {
    Configuration::ALL
        .iter()
        .map(|&c| {
            let mut list_only = 0;
            let mut merged = 0;
            let (mut sum, mut worst) = (0u64, 0u64);
            for set in sets {
                let f = set.filters();
                let o = FlexOptions::new(c);
                if flex_plan(&f, o.merge(false)).is_ok() {
                    list_only += 1;
                }
                if flex_plan(&f, o).is_ok() {
                    merged += 1;
                } else if let Ok(t) = flex_plan(&f, o.superset(true)) {
                    sum += t.superset_extra();
                    worst = worst.max(t.superset_extra());
                }
            }
            (c, list_only, merged, sum, worst)
        })
        .collect()
}

/// The planner-quality section of `docs/benchmarks.md` (Markdown).
pub fn report() -> String {
    let sets = parse(CORPUS).expect("the shipped corpus parses");
    let rows = bxcan_rows(&sets);
    render(&sets, &rows, &flexcan_rows(&sets))
}

fn render(
    sets: &[IdSet],
    rows: &[BxRow],
    flex_rows: &[(Configuration, usize, usize, u64, u64)],
) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let n = sets.len();
    let ids: usize = sets.iter().map(IdSet::len).sum();
    let _ = writeln!(s, "## Filter planner quality\n");
    let _ = writeln!(
        s,
        "Corpus: `bench/data/dbc_ids.txt`, {n} identifier sets of public vehicle DBC files \
         ({ids} identifiers, 1–{} per set; one exact data-frame filter per identifier).\n",
        sets.iter().map(IdSet::len).max().unwrap_or(0)
    );
    let fit = |b: u64| b <= 28;
    let lo_fit = rows.iter().filter(|r| fit(r.list_only)).count();
    let m_fit = rows.iter().filter(|r| fit(r.merged)).count();
    let both: Vec<&BxRow> = rows.iter().filter(|r| fit(r.list_only)).collect();
    let lo_banks: u64 = both.iter().map(|r| r.list_only).sum();
    let m_banks_same: u64 = both.iter().map(|r| r.merged).sum();
    let m_rows: Vec<&BxRow> = rows.iter().filter(|r| fit(r.merged)).collect();
    let m_banks: u64 = m_rows.iter().map(|r| r.merged).sum();
    let bound_banks: u64 = m_rows.iter().map(|r| r.bound.0).sum();
    let exact_bounds = rows.iter().filter(|r| r.bound.1).count();
    let at_bound = m_rows.iter().filter(|r| r.merged == r.bound.0).count();
    let within_2 = m_rows
        .iter()
        .filter(|r| r.merged as f64 <= r.bound.0 as f64 * 1.02)
        .count();
    let worst = m_rows
        .iter()
        .max_by(|a, b| {
            let ra = a.merged as f64 / a.bound.0.max(1) as f64;
            let rb = b.merged as f64 / b.bound.0.max(1) as f64;
            ra.total_cmp(&rb)
        })
        .map(|r| format!("{} ({} banks, bound {})", r.name, r.merged, r.bound.0))
        .unwrap_or_default();
    let _ = writeln!(s, "### bxCAN (28 banks)\n");
    let _ = writeln!(s, "| measure | list only (v1) | merged (v2) |");
    let _ = writeln!(s, "|---|---:|---:|");
    let _ = writeln!(s, "| sets planned exactly | {lo_fit}/{n} | {m_fit}/{n} |");
    let _ = writeln!(
        s,
        "| banks on the {} sets both plan | {lo_banks} | {m_banks_same} |",
        both.len()
    );
    let _ = writeln!(
        s,
        "| banks on the {} sets v2 plans / exact lower bound | | {m_banks} / {bound_banks} ({:.3}×) |",
        m_rows.len(),
        m_banks as f64 / bound_banks.max(1) as f64
    );
    let _ = writeln!(
        s,
        "| sets at the bound / within 2 % | | {at_bound} / {within_2} (worst: {worst}) |"
    );
    let supersets: Vec<&BxRow> = rows.iter().filter(|r| r.superset_extra.is_some()).collect();
    let _ = writeln!(
        s,
        "\nLower bounds exact (cover search finished) for {exact_bounds}/{n} sets.\n"
    );
    let _ = writeln!(
        s,
        "Sets that fit no exact plan: {}; in superset mode each fits 28 banks, the hardware \
         accepting these extra identifiers (the driver drops them):\n",
        supersets.len()
    );
    if !supersets.is_empty() {
        let _ = writeln!(
            s,
            "| set | identifiers | banks needed exactly | extra identifiers |"
        );
        let _ = writeln!(s, "|---|---:|---:|---:|");
        for r in &supersets {
            let extra = match r.superset_extra {
                Some(u64::MAX) => "no plan".to_string(),
                Some(x) => x.to_string(),
                None => String::new(),
            };
            let _ = writeln!(s, "| {} | {} | {} | {} |", r.name, r.ids, r.merged, extra);
        }
    }
    let _ = writeln!(s, "\n### FlexCAN (Rx FIFO ID table)\n");
    let _ = writeln!(
        s,
        "| configuration | sets fitting, one element per id | sets fitting, merged | superset extras of the others (sum / worst) |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|");
    for (c, lo, m, sum, worst) in flex_rows {
        let _ = writeln!(
            s,
            "| {}/{} | {lo}/{n} | {m}/{n} | {sum} / {worst} |",
            c.primary_filter_capacity(),
            c.secondary_filter_capacity()
        );
    }
    s
}
