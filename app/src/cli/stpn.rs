//! `vigie stpn NET`: a stochastic timed Petri net's state graph and its analyses
//! (`core/src/stpn.rs`).

use std::path::Path;
use std::process::ExitCode;
use vigie_core::stpn::{NetFile, Q};

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

pub(crate) fn run(
    file: &Path,
    failed: Option<&str>,
    observe: &[String],
    json: bool,
) -> anyhow::Result<ExitCode> {
    let render = |p: &[vigie_core::diag::Problem]| vigie_core::diag::render(p);
    let (net, text) = NetFile::load(file).map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
    let net = net
        .check(file, &text)
        .map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
    let g = net
        .state_graph()
        .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
    if json {
        println!("{}", serde_json::to_string_pretty(&g)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!("{} states, {} arcs", g.states.len(), g.arcs.len());
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
            "steady state (home states: the one terminal component), mean cycle {} from state {}:",
            shown(&cycle),
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
