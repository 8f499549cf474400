//! `vigie stpn NET`: a stochastic timed Petri net's state graph and its analyses
//! (`core/src/stpn.rs`).

use std::path::Path;
use std::process::ExitCode;
use vigie_core::stpn::{Net, NetFile, Outcome, Q, StateGraph};

/// A rational with its decimal value.
fn shown(q: &Q) -> String {
    let n: f64 = q.numer().to_string().parse().unwrap_or(f64::NAN);
    let d: f64 = q.denom().to_string().parse().unwrap_or(f64::NAN);
    if q.is_integer() {
        q.to_string()
    } else {
        format!("{q} ({:.6})", n / d)
    }
}

/// A time in the net's unit, with its decimal value.
fn time(q: &Q, unit: &str) -> String {
    format!("{} {unit}", shown(q))
}

/// One answer, as the plant engineer reads it.
fn print_outcome(net: &Net, o: &Outcome) {
    let unit = &net.unit;
    match o {
        Outcome::View { name, arcs } => {
            println!("view `{name}`: [mean time, probability]");
            for a in arcs {
                println!(
                    "  {} -> {}: [{}, {}]",
                    a.from,
                    a.to,
                    time(&a.t, unit),
                    shown(&a.p)
                );
            }
        }
        Outcome::Passage { name, p, mean } => match mean {
            Some(t) if *p == Q::from_integer(1.into()) => println!("{name}: {}", time(t, unit)),
            Some(t) => println!("{name}: {} with probability {}", time(t, unit), shown(p)),
            None => println!("{name}: never"),
        },
        Outcome::Reach {
            name,
            p,
            first,
            stay,
        } => match first {
            None => println!("{name}: never reached"),
            Some(t) => println!(
                "{name}: reached with probability {} after {}, {}",
                shown(p),
                time(t, unit),
                match stay {
                    Some(s) => format!("lasts {}", time(s, unit)),
                    None => "never left".into(),
                }
            ),
        },
        Outcome::Timeline { name, events } => {
            println!("timeline `{name}`:");
            for e in events {
                let label = net
                    .transitions
                    .iter()
                    .position(|t| *t == e.event)
                    .map(|i| net.labels[i].as_str())
                    .unwrap_or("");
                let p = if e.p == Q::from_integer(1.into()) {
                    String::new()
                } else {
                    format!(" (probability {})", shown(&e.p))
                };
                println!("  {}: {} {label}{p}", time(&e.date, unit), e.event);
            }
        }
        Outcome::Unanswered { name, why } => println!("{name}: not answered: {why}"),
    }
}

/// The state graph, its steady state, the queries and their answers, as JSON.
fn json_report(net: &Net, g: &StateGraph, outcomes: &[Outcome]) -> serde_json::Value {
    #[derive(serde::Serialize)]
    struct Report<'a> {
        places: &'a [String],
        transitions: &'a [String],
        ticks_per_unit: u64,
        graph: &'a vigie_core::stpn::StateGraph,
        /// The steady state's time shares, by state, when there is one.
        steady: Option<Vec<(usize, String)>>,
        asked: &'a [vigie_core::stpn::QueryDef],
        queries: &'a [Outcome],
    }
    let terminal = g.terminal_components();
    let steady = match terminal.as_slice() {
        [c] if c.len() > 1 => g
            .steady_state(c)
            .map(|(pi, _)| pi.into_iter().map(|(s, p)| (s, p.to_string())).collect()),
        _ => None,
    };
    let report = Report {
        places: &net.places,
        transitions: &net.transitions,
        ticks_per_unit: net.ticks_per_unit,
        graph: g,
        steady,
        asked: &net.queries,
        queries: outcomes,
    };
    serde_json::to_value(&report).unwrap_or_default()
}

/// Sinks, terminal components and the steady state.
fn print_structure(net: &Net, g: &StateGraph) {
    let sinks = g.sinks();
    println!(
        "sinks: {}",
        if sinks.is_empty() {
            "none".into()
        } else {
            format!("{sinks:?}")
        }
    );
    let terminal = g.terminal_components();
    println!("terminal components: {}", terminal.len());
    if let [c] = terminal.as_slice()
        && c.len() > 1
        && let Some((pi, cycle)) = g.steady_state(c)
    {
        println!(
            "steady state (home states: the one terminal component), mean return time to state {1}: {0}:",
            time(
                &(cycle / Q::from_integer(net.ticks_per_unit.into())),
                &net.unit
            ),
            c[0]
        );
        for (s, p) in pi.iter().filter(|(_, p)| p.to_string() != "0") {
            let marked: Vec<&str> = g.states[*s]
                .marking
                .iter()
                .enumerate()
                .filter(|(_, k)| **k > 0)
                .map(|(i, _)| net.places[i].as_str())
                .collect();
            println!("  state {s} ({}): {}", marked.join(", "), shown(p));
        }
    }
}

pub(crate) fn run(
    file: &Path,
    with: &[String],
    failed: Option<&str>,
    observe: &[String],
    json: bool,
) -> anyhow::Result<ExitCode> {
    let render = |p: &[vigie_core::diag::Problem]| vigie_core::diag::render(p);
    let (net, text) = NetFile::load(file).map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
    let net = net
        .variant(file, &text, with)
        .map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
    let g = net
        .state_graph()
        .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
    let started = std::time::Instant::now();
    let outcomes = net.answer(&g);
    let analysed = started.elapsed();
    if json {
        let report = json_report(&net, &g, &outcomes);
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "{} states, {} arcs{}",
        g.states.len(),
        g.arcs.len(),
        if with.is_empty() {
            String::new()
        } else {
            format!(" (with {})", with.join(", "))
        }
    );
    print_structure(&net, &g);
    for o in &outcomes {
        print_outcome(&net, o);
    }
    if !outcomes.is_empty() {
        eprintln!("analyses: {:.3} s", analysed.as_secs_f64());
    }
    if !observe.is_empty() {
        let mut states = Vec::new();
        for place in observe {
            let Some(k) = net.places.iter().position(|p| p == place) else {
                anyhow::bail!("{}: `{place}` is not a place of the net", file.display());
            };
            states.extend(g.marked(k));
        }
        states.sort_unstable();
        states.dedup();
        let view = g.abstract_view(&states).ok_or_else(|| {
            anyhow::anyhow!("the unobservable states loop forever: no abstract view")
        })?;
        println!(
            "abstract view on {} states ({}):",
            states.len(),
            observe.join(", ")
        );
        for (o, to, f, t) in &view {
            println!("  {o} -> {to}: [{}, {}]", shown(t), shown(f));
        }
    }
    if let Some(place) = failed {
        let Some(k) = net.places.iter().position(|p| p == place) else {
            anyhow::bail!("{}: `{place}` is not a place of the net", file.display());
        };
        let failures = g.marked(k);
        match g.mttf(&failures) {
            Some(t) => println!("MTFF to `{place}`: {}", shown(&t)),
            None => anyhow::bail!(
                "`{place}` is not reached with probability 1 from the initial marking: no MTFF"
            ),
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// `vigie bench-stpn`: per net and per variant (every subset of its flags), the state
/// graph's size, the median time to build it and the time to answer its queries.
pub(crate) fn bench(nets: &[std::path::PathBuf], repeat: usize) -> anyhow::Result<ExitCode> {
    let nets: Vec<std::path::PathBuf> = if nets.is_empty() {
        let dir = Path::new("layouts/substation/nets");
        let mut found: Vec<_> = std::fs::read_dir(dir)
            .map_err(|e| anyhow::anyhow!("{}: {e} (run from the repository root)", dir.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "ron"))
            .collect();
        found.sort();
        found
    } else {
        nets.to_vec()
    };
    let render = |p: &[vigie_core::diag::Problem]| vigie_core::diag::render(p);
    println!(
        "{:<32} {:<24} {:>7} {:>7} {:>10} {:>12}",
        "net", "variant", "states", "arcs", "build ms", "analyses ms"
    );
    for file in &nets {
        let (def, text) = NetFile::load(file).map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
        let k = def.flags.len();
        for mask in 0..(1usize << k) {
            let flags: Vec<String> = (0..k)
                .filter(|b| mask & (1 << b) != 0)
                .map(|b| def.flags[b].clone())
                .collect();
            let net = def
                .variant(file, &text, &flags)
                .map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
            let mut times = Vec::new();
            let mut graph = None;
            for _ in 0..repeat.max(1) {
                let started = std::time::Instant::now();
                let g = net
                    .state_graph()
                    .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
                times.push(started.elapsed().as_secs_f64() * 1e3);
                graph = Some(g);
            }
            times.sort_by(f64::total_cmp);
            let Some(g) = graph else { continue };
            let started = std::time::Instant::now();
            let answers = net.answer(&g);
            let analysed = started.elapsed().as_secs_f64() * 1e3;
            let unanswered = answers
                .iter()
                .filter(|o| matches!(o, Outcome::Unanswered { .. }))
                .count();
            println!(
                "{:<32} {:<24} {:>7} {:>7} {:>10.2} {:>12.2}{}",
                file.file_name()
                    .map(|n| n.to_string_lossy())
                    .unwrap_or_default(),
                if flags.is_empty() {
                    "-".to_string()
                } else {
                    flags.join(",")
                },
                g.states.len(),
                g.arcs.len(),
                times[times.len() / 2],
                analysed,
                if unanswered > 0 {
                    format!("  ({unanswered} queries unanswered)")
                } else {
                    String::new()
                }
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}
