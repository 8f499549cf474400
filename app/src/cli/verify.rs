//! `vigie verify`: exhaustive verification of the constraint set on the abstract plant
//! model, the SPIN cross-check, and the compiled-filter benchmarks.

use std::process::ExitCode;
use std::time::Instant;
use vigie_core::dtree::{CompiledFilter, Tests};
use vigie_core::emulator::Layout;
use vigie_core::frame::Frame;
use vigie_core::verify::{self, Model, Options, promela};

/// Arguments of `vigie verify`.
#[derive(clap::Args, Debug)]
pub(crate) struct VerifyArgs {
    #[command(flatten)]
    pub(crate) plant: super::PlantArg,
    /// Largest number of boxes in the plant at once.
    #[arg(long, default_value_t = 2)]
    pub(crate) max_boxes: usize,
    /// Also tell which constraints are necessary (a hazard becomes reachable without
    /// them) and which are redundant, on a model with this many boxes.
    #[arg(long, num_args = 0..=1, default_missing_value = "1")]
    pub(crate) necessity: Option<usize>,
    /// Also run SPIN on the same model and compare.
    #[arg(long)]
    pub(crate) spin: bool,
    /// Print timing figures: verification vs SPIN, compiled filter forms vs direct.
    #[arg(long)]
    pub(crate) bench: bool,
    /// Print the JSON report.
    #[arg(long)]
    pub(crate) json: bool,
    /// Write counterexamples here (trace CSV replayed in the emulator, Promela model).
    #[arg(long)]
    pub(crate) out: Option<std::path::PathBuf>,
    /// On a plant of components: stop each sub-plant's search after this many
    /// transitions (it is then reported as not proved).
    #[arg(long, default_value_t = verify::components::MAX_TRANSITIONS)]
    pub(crate) max_transitions: u64,
}

fn ns_per(iters: u32, mut f: impl FnMut(u32) -> bool) -> f64 {
    let mut sink = 0u32;
    let t0 = Instant::now();
    for i in 0..iters {
        sink = sink.wrapping_add(u32::from(f(i)));
    }
    let ns = t0.elapsed().as_nanos() as f64 / f64::from(iters);
    std::hint::black_box(sink);
    ns
}

pub(crate) fn run(args: &VerifyArgs) -> anyhow::Result<ExitCode> {
    let dir = args.plant.plant.as_path();
    let (bundle, _) = super::load_bundle(dir)?;
    // A turntable cell (the station's kind) has its own abstract model; any other
    // plant of components is searched per sub-plant.
    let layout = match verify::subject_of(dir)
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?
    {
        verify::Subject::Cell(layout) => *layout,
        verify::Subject::Parts(desc) => return run_components(args, &bundle, &desc),
    };
    let opts = Options {
        max_boxes: args.max_boxes,
        necessity_boxes: args.necessity,
    };
    let model = Model::new(&bundle, &layout, opts.max_boxes)
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&[p])))?;
    let t0 = Instant::now();
    let mut report = verify::verify(
        &bundle,
        &layout,
        &Options {
            necessity_boxes: None,
            ..opts.clone()
        },
    )
    .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&[p])))?;
    let t_full = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    if let Some(nb) = opts.necessity_boxes {
        report.constraints = verify::necessity(&bundle, &layout, nb)
            .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&[p])))?;
    }
    let t_all = t0.elapsed().as_secs_f64();
    let full = &report.full;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        let g = &report.geometry;
        println!(
            "plant: {}\nabstraction: cell {} mm, step {:.1} ms, rotation {}/{} mdeg per step, at most {} boxes, exits always running, safety contactors held ON (only the fallback releases them)",
            report.plant,
            g.cell_mm,
            g.step_us as f64 / 1000.0,
            g.rot_out / 1000,
            g.rot_back / 1000,
            report.max_boxes
        );
        println!(
            "explored: {} states, {} transitions in {:.2} s (safety, permissiveness, invariants)",
            full.states, full.transitions, t_full
        );
        println!(
            "assumptions: at most {} boxes at once, exits always running, safety contactors held ON and never welded or dead, boxes travel forward on the feed line, PLC cycle shorter than a step",
            report.max_boxes
        );
        match &report.full.hazard {
            None => println!("SAFETY: proved (no hazard reachable)"),
            Some((kind, trace)) => {
                print_counterexample(args, &bundle, &layout, kind, trace, g.step_us)?
            }
        }
        if report.full.no_fallback.is_some() {
            println!("FALLBACK: some reachable context has no fallback vector");
        }
        println!("hazard kinds reachable: {:?}", report.full.hazard_kinds);
        print_roles(&report, opts.necessity_boxes, t_all);
    }
    if args.spin || args.bench {
        compare_with_spin(args, &model, &bundle, full, t_full)?;
    }
    if args.bench {
        bench_compiled(&bundle)?;
    }
    Ok(if report.safe && report.permissive {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// A plant of components: each sub-plant verified on its own (see
/// [`verify::components`]), with and without the filter.
fn run_components(
    args: &VerifyArgs,
    bundle: &vigie_core::bundle::PlantBundle,
    desc: &vigie_core::machine::description::Components,
) -> anyhow::Result<ExitCode> {
    let t0 = Instant::now();
    let report = verify::components::verify_components_within(bundle, desc, args.max_transitions)
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&[p])))?;
    let secs = t0.elapsed().as_secs_f64();
    let unsafe_parts = report.unsafe_parts();
    let unverified = report.unproved();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!(
            "plant: {}\nabstraction: one component at a time (a conveyor with the axes its feeder and taker read), its travel cut into zones at its sensors' and dangers' edges, any control, 10 ms cycles ({secs:.2} s)",
            report.plant
        );
        println!("assumptions: {}", report.assumptions.join("; "));
        for p in &report.parts {
            print_part(p);
        }
        if !report.not_modelled.is_empty() {
            println!(
                "not modelled (detectors, links): {}",
                report.not_modelled.join(", ")
            );
        }
        println!(
            "SAFETY: {}",
            if unsafe_parts.is_empty() && !unverified {
                "proved for every modelled component (no hazard reachable with the filter)"
            } else if unsafe_parts.is_empty() {
                "no hazard reachable in the components verified; some were not verified"
            } else {
                "VIOLATED"
            }
        );
    }
    Ok(if unsafe_parts.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// One sub-plant's lines of `vigie verify`.
fn print_part(p: &verify::components::SubReport) {
    let hazards: Vec<String> = p.hazards.iter().map(ToString::to_string).collect();
    let with = if p.with.is_empty() {
        String::new()
    } else {
        format!(" (with {})", p.with.join(", "))
    };
    println!(
        "{}{with}: {} | guarded by {} | free inputs [{}] | outputs [{}]",
        p.component,
        hazards.join(", "),
        if p.constraints.is_empty() {
            "no constraint".to_string()
        } else {
            p.constraints.join(", ")
        },
        p.free_inputs.join(" "),
        p.free_outputs.join(" ")
    );
    if let Some(why) = &p.skipped {
        println!("  NOT VERIFIED: {why}");
        return;
    }
    let real: Vec<String> = p
        .without_filter
        .iter()
        .map(|r| format!("{} ({} cycles)", r.hazard, r.trace.len()))
        .collect();
    println!(
        "  without the filter: {}",
        if real.is_empty() && p.without_filter_truncated {
            "no hazard found before the search stopped at its limit".to_string()
        } else if real.is_empty() {
            "no hazard reachable".to_string()
        } else {
            real.join(", ")
        }
    );
    println!(
        "  with the filter: {} states, {} transitions{}: {}",
        p.states,
        p.transitions,
        if p.truncated { " (TRUNCATED)" } else { "" },
        {
            let v: Vec<String> = p.violated().map(|r| r.hazard.to_string()).collect();
            if !v.is_empty() {
                format!("VIOLATED: {}", v.join(", "))
            } else if p.truncated {
                "NOT PROVED (the search stopped at its limit)".to_string()
            } else {
                "SAFE".to_string()
            }
        }
    );
    if !p.uncontrollable.is_empty() {
        let v: Vec<String> = p.uncontrollable.iter().map(ToString::to_string).collect();
        println!(
            "  ENVIRONMENT: {} reachable with every output at its safe value (the free inputs make it; no constraint can prevent it)",
            v.join(", ")
        );
    }
    for r in p.violated() {
        for s in r.trace.iter().rev().take(4).rev() {
            println!(
                "    at {}  in[{}] commanded[{}] applied[{}]",
                s.zone,
                s.inputs.join(" "),
                s.commanded.join(" "),
                s.applied.join(" ")
            );
        }
    }
}

/// Prints the last steps of the counterexample and its replay in the emulator; with
/// `--out`, writes it (CSV, JSON, scenario to open in the console).
fn print_counterexample(
    args: &VerifyArgs,
    bundle: &vigie_core::bundle::PlantBundle,
    layout: &Layout,
    kind: &str,
    trace: &verify::Trace,
    step_us: i64,
) -> anyhow::Result<()> {
    let dir = args.plant.plant.as_path();
    println!(
        "SAFETY: VIOLATED: {kind} reachable in {} steps; last steps:",
        trace.steps.len()
    );
    for s in trace.steps.iter().rev().take(4).rev() {
        println!(
            "  t={:>6} ms  in[{}] obs[{}] applied[{}]  {}",
            s.time_ms, s.inputs, s.observers, s.applied, s.plant
        );
    }
    let rp = verify::replay(layout, bundle, trace, step_us, 10)
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&[p])))?;
    match rp.hazards.first() {
        Some(h) => println!(
            "  replayed in the emulator: {:?} at {} ms ({}) — a real flaw of the constraint set on this plant",
            h.kind, h.time_ms, h.place
        ),
        None => {
            println!("  replayed in the emulator: no hazard (abstraction artefact)")
        }
    }
    if let Some(out) = &args.out {
        std::fs::create_dir_all(out)?;
        std::fs::write(out.join("counterexample.csv"), &rp.csv)?;
        std::fs::write(
            out.join("counterexample.json"),
            serde_json::to_string_pretty(trace)?,
        )?;
        let plant_abs = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
        let sc = verify::scenario::write(
            out,
            trace,
            &bundle.plant,
            &plant_abs.to_string_lossy(),
            step_us,
        )?;
        println!(
            "  trace written to {}",
            out.join("counterexample.csv").display()
        );
        println!(
            "  open it in the console: vigie run {}   (or --headless for the report)",
            sc.display()
        );
    }
    Ok(())
}

/// Prints permissiveness per side, the invariants proved or refuted and each
/// constraint's necessity (with the time of that analysis).
fn print_roles(report: &verify::VerifyReport, necessity_boxes: Option<usize>, t_all: f64) {
    for (side, name) in ["left (+u)", "right (-u)"].iter().enumerate() {
        println!(
            "PERMISSIVENESS {name}: delivery {} ; from every reachable state: {}",
            report.full.delivered[side]
                .as_ref()
                .map_or("UNREACHABLE".to_string(), |t| format!(
                    "reachable in {} steps",
                    t.steps.len()
                )),
            if report.full.always_deliverable[side] {
                "yes".to_string()
            } else {
                format!(
                    "NO (stuck after {} steps: {})",
                    report.full.stuck[side]
                        .as_ref()
                        .map_or(0, |t| t.steps.len()),
                    report.full.stuck[side]
                        .as_ref()
                        .and_then(|t| t.steps.last())
                        .map_or(String::new(), |s| format!(
                            "in[{}] obs[{}] {}",
                            s.inputs, s.observers, s.plant
                        ))
                )
            }
        );
    }
    for i in &report.invariants {
        println!(
            "{:<5} {:<24} {}",
            i.id,
            i.source,
            if i.proved {
                "proved".to_string()
            } else {
                format!(
                    "REFUTED in {} steps",
                    i.counterexample.as_ref().map_or(0, |t| t.steps.len())
                )
            }
        );
    }
    for c in &report.constraints {
        println!(
            "{:<6} {}",
            c.id,
            if c.necessary {
                format!(
                    "necessary: without it {} in {} steps ({} states)",
                    c.hazard.as_deref().unwrap_or("?"),
                    c.steps.unwrap_or(0),
                    c.states
                )
            } else {
                format!("redundant for this model ({} states)", c.states)
            }
        );
    }
    if !report.constraints.is_empty() {
        println!(
            "necessity analysis ({} box(es), one exploration per constraint): {:.2} s",
            necessity_boxes.unwrap_or(1),
            t_all
        );
    }
}

/// Runs SPIN on the Promela model (written with `--out`) and says whether it agrees
/// with vigie's exploration.
fn compare_with_spin(
    args: &VerifyArgs,
    model: &Model,
    bundle: &vigie_core::bundle::PlantBundle,
    full: &verify::Exploration,
    t_full: f64,
) -> anyhow::Result<()> {
    let text = promela::generate(model, &bundle.constraints, &bundle.symbols);
    if let Some(out) = &args.out {
        std::fs::create_dir_all(out)?;
        std::fs::write(out.join("model.pml"), &text)?;
    }
    let t0 = Instant::now();
    let v = promela::run_spin(&text, 0, false)
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&[p])))?;
    let secs = t0.elapsed().as_secs_f64();
    let mut mine: Vec<String> = full.hazard_kinds.iter().map(|(k, _)| k.clone()).collect();
    mine.sort();
    let agree = v.hazards == mine
        && v.delivered == [full.delivered[0].is_some(), full.delivered[1].is_some()]
        && v.no_fallback == full.no_fallback.is_some();
    println!(
        "SPIN: {} states stored in {:.2} s (spin+gcc+pan), hazards {:?}, deliveries {:?}, no fallback {}, complete {} — {}",
        v.states,
        secs,
        v.hazards,
        v.delivered,
        v.no_fallback,
        v.complete,
        if agree {
            "AGREES with vigie"
        } else {
            "DISAGREES with vigie"
        }
    );
    println!("vigie: {} states in {:.2} s", full.states, t_full);
    Ok(())
}

fn bench_compiled(bundle: &vigie_core::bundle::PlantBundle) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let c1 = CompiledFilter::new(&bundle.constraints, Tests::Single)
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&[p])))?;
    let build1 = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let c2 = CompiledFilter::new(&bundle.constraints, Tests::Pairs)
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&[p])))?;
    let build2 = t0.elapsed().as_secs_f64();
    let filter = vigie_core::filter::Filter::new(&bundle.constraints, bundle.plant.outputs.len());
    let n = c1.vars.len();
    let mut frames = Vec::new();
    let mut rng = vigie_core::synthetic::SplitMix64::new(42);
    for _ in 0..1024 {
        let mut f = Frame::new(bundle.symbols.sizes());
        c1.unpack_into(rng.next_u64() & ((1u64 << n) - 1), &mut f);
        frames.push(f);
    }
    let packed: Vec<u64> = frames.iter().map(|f| c1.pack(f)).collect();
    let iters = 2_000_000;
    let mut v = Vec::new();
    let direct = ns_per(iters, |i| {
        filter.violations_into(&frames[(i & 1023) as usize], &mut v);
        !v.is_empty()
    });
    let t1 = c1.tree.clone();
    let t2 = c2.tree.clone();
    for (name, s) in [
        ("w=1", t1.as_ref().map(|t| t.stats())),
        ("w=2", t2.as_ref().map(|t| t.stats())),
    ] {
        if let Some(s) = s {
            println!(
                "station tree {name}: {} tests, {} leaves, depth {}, mean {:.3} tests over {} support variables",
                s.internal, s.leaves, s.depth, s.mean, n
            );
        }
    }
    println!("station tree build: w=1 {build1:.3} s, w=2 {build2:.3} s");
    let tree1 = t1.map(|t| ns_per(iters, |i| t.eval(packed[(i & 1023) as usize])));
    let tree2 = t2.map(|t| ns_per(iters, |i| t.eval(packed[(i & 1023) as usize])));
    let masks = ns_per(iters, |i| c1.masks.eval(packed[(i & 1023) as usize]));
    let pack = ns_per(iters, |i| c1.pack(&frames[(i & 1023) as usize]) & 1 == 1);
    println!(
        "station per cycle: direct (Filter::violations_into) {direct:.1} ns; tree w=1 {:.1} ns; tree w=2 {:.1} ns; masks {masks:.1} ns (+ packing the frame {pack:.1} ns)",
        tree1.unwrap_or(f64::NAN),
        tree2.unwrap_or(f64::NAN)
    );
    // Synthetic 10,000-constraint plant: support too large for the tree; masks over
    // the whole frame via the filter's own packed literals vs the sparse mask rows.
    let syn = vigie_core::synthetic::generate(10_000, 10_000, 42);
    let sf = vigie_core::filter::Filter::new(&syn.constraints, syn.plant.outputs.len());
    let mut sframes = Vec::new();
    let mut rng = vigie_core::synthetic::SplitMix64::new(7);
    for _ in 0..64 {
        let mut f = Frame::new(syn.symbols.sizes());
        for s in 0..4 {
            for t in [&mut f.now[s], &mut f.prev[s]] {
                for k in 0..t.len() {
                    t.set(k, rng.chance(1, 2));
                }
            }
        }
        sframes.push(f);
    }
    let sd = ns_per(2000, |i| {
        sf.violations_into(&sframes[(i & 63) as usize], &mut v);
        !v.is_empty()
    });
    let sm = vigie_core::dtree::SparseMasks::new(&syn.constraints);
    let smn = ns_per(2000, |i| sm.eval(&sframes[(i & 63) as usize]));
    println!(
        "synthetic 10,000 constraints per cycle: direct {sd:.0} ns; sparse mask table {smn:.0} ns; tree: not applicable (support of {} variables cannot be enumerated)",
        sm.support()
    );
    Ok(())
}
