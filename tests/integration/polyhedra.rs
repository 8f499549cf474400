//! The stopwatch synthesis's polyhedra (`core/src/swa/poly.rs`) against an independent
//! library, the Parma Polyhedra Library (`pplpy`, pinned in the test venv): random
//! polyhedra with strict and non-strict bounds, and the four operations the synthesis
//! is made of (time elapse, projection, intersection, redundancy removal), each result
//! compared as a set. And `vigie synthesize` on the thesis's workshop.

use crate::live::repo;
use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use vigie_core::swa::poly::{HalfSpace, Poly, Q};

fn python() -> PathBuf {
    let venv = std::env::var_os("VIGIE_VENV").map_or_else(|| repo().join(".venv"), PathBuf::from);
    let py = venv.join("bin/python");
    assert!(
        py.is_file(),
        "the test venv is missing ({} not found): the polyhedra cross-check needs the pinned \
         `pplpy`. Run `scripts/test.sh` once, or `python3 -m venv .venv && .venv/bin/pip \
         install -r requirements-test.txt` at the repository root (or set VIGIE_VENV)",
        py.display()
    );
    py
}

/// A small deterministic generator (the cases are the same on every run).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self, n: u64) -> i128 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        i128::from(((self.0 >> 33) % n) as u16)
    }
}

fn q(x: &Q) -> serde_json::Value {
    serde_json::json!([
        x.numer().to_string().parse::<i64>().unwrap(),
        x.denom().to_string().parse::<i64>().unwrap()
    ])
}

fn rows(p: &Poly) -> serde_json::Value {
    if p.is_empty() {
        return serde_json::Value::Null;
    }
    p.half_spaces()
        .iter()
        .map(|h| serde_json::json!([h.a.iter().map(q).collect::<Vec<_>>(), q(&h.b), h.strict]))
        .collect()
}

fn random_poly(g: &mut Lcg, dim: usize) -> Poly {
    let mut p = Poly::universe(dim);
    // Clocks: non-negative, bounded.
    for k in 0..dim {
        let mut a = vec![Q::zero(); dim];
        a[k] = -Q::one();
        p.add(HalfSpace::le(a.clone(), Q::zero()));
        a[k] = Q::one();
        p.add(HalfSpace {
            a,
            b: Q::int(3 + g.next(8)),
            strict: g.next(2) == 1,
        });
    }
    for _ in 0..g.next(4) + 1 {
        let a: Vec<Q> = (0..dim).map(|_| Q::int(g.next(5) - 2)).collect();
        p.add(HalfSpace {
            a,
            b: Q::int(g.next(9) - 2),
            strict: g.next(2) == 1,
        });
    }
    p
}

#[test]
fn polyhedra_agree_with_the_parma_polyhedra_library() {
    let mut g = Lcg(2008);
    let mut cases = Vec::new();
    for i in 0..240 {
        let dim = 2 + (i % 3);
        let p = random_poly(&mut g, dim);
        let input = rows(&p);
        if input.is_null() {
            continue;
        }
        let case = match i % 4 {
            0 => {
                let rates: Vec<Q> = (0..dim).map(|_| Q::int(g.next(2))).collect();
                let r = p.elapse(&rates, true);
                serde_json::json!({"dim": dim, "input": input, "op": "elapse",
                    "rates": rates.iter().map(|x| x.numer().to_string().parse::<i64>().unwrap()).collect::<Vec<_>>(),
                    "result": rows(&r)})
            }
            1 => {
                let var = usize::try_from(g.next(dim as u64)).unwrap();
                serde_json::json!({"dim": dim, "input": input, "op": "exists", "var": var,
                    "result": rows(&p.exists(var))})
            }
            2 => {
                let other = random_poly(&mut g, dim);
                serde_json::json!({"dim": dim, "input": input, "op": "intersect",
                    "other": rows(&other), "result": rows(&p.intersect(&other))})
            }
            _ => serde_json::json!({"dim": dim, "input": input, "op": "minimize",
                    "result": rows(&p.minimize())}),
        };
        if case.get("other").is_some_and(serde_json::Value::is_null) {
            continue;
        }
        cases.push(case);
    }
    assert!(cases.len() > 150, "{} cases", cases.len());
    let mut child = Command::new(python())
        .arg(repo().join("tests/peers/ppl_check.py"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python runs");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(serde_json::to_string(&cases).unwrap().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{said}");
    assert!(
        said.contains(&format!("{} cases, 0 mismatches", cases.len())),
        "{said}"
    );
}

/// `vigie synthesize` on the thesis's workshop automata: the 12 locations, and the
/// committed regions file is what they give (`--check`); a changed bound makes it stale.
#[test]
fn synthesize_command_reproduces_the_workshop_regions() {
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_vigie"))
            .args(args)
            .current_dir(repo())
            .output()
            .unwrap()
    };
    let out = run(&["synthesize", "layouts/workshop/workshop.swa.ron", "--check"]);
    let said = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "{said}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(said.contains("12 locations (0 unreachable"), "{said}");
    assert!(said.contains("is up to date"), "{said}");
    // A bound changed since: the committed regions are refused.
    let dir = std::env::temp_dir().join(format!("vigie-synth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(repo().join("layouts/workshop/workshop.swa.ron")).unwrap();
    let changed = dir.join("workshop.swa.ron");
    std::fs::write(&changed, text.replace("x2 <= 5000", "x2 <= 6000")).unwrap();
    std::fs::copy(
        repo().join("layouts/workshop/workshop.regions.ron"),
        dir.join("workshop.regions.ron"),
    )
    .unwrap();
    let out = run(&["synthesize", changed.to_str().unwrap(), "--check"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("V1503"));
    // An unknown clock: the file, line and column, and the code.
    std::fs::write(
        &changed,
        text.replace("guard: \"x2 < 5000\"", "guard: \"z < 5000\""),
    )
    .unwrap();
    let out = run(&["synthesize", changed.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!out.status.success());
    assert!(
        err.contains("workshop.swa.ron:")
            && err.contains("V1501")
            && err.contains("unknown clock `z`"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
