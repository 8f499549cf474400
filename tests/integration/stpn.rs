//! `vigie stpn` on seed 002's nets (`layouts/substation/nets/`), cross-checked by an
//! independent exact Markov-chain computation in sympy (`tests/peers/stpn_check.py`,
//! sympy pinned in the test venv): the steady states' time shares, the MTFFs and first
//! passages, the double fault's reachability, each variant of each net.

use crate::live::{python, repo};
use crate::vigie;
use std::io::Write;
use std::process::{Command, Stdio};

fn said(out: &std::process::Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

#[test]
fn sympy_agrees_with_every_analysis_of_the_thesis_s_nets() {
    let fip = "layouts/substation/nets/fip-refresh-promptness.ron";
    let selectivity = "layouts/substation/nets/logical-selectivity.ron";
    for (net, with, at_least) in [
        (fip, "", 30),
        (fip, "write_loss", 60),
        (fip, "sync_loss", 60),
        (fip, "write_loss,sync_loss", 200),
        (selectivity, "", 2),
        (selectivity, "period_50ms", 2),
        (selectivity, "period_50ms,late_onset", 2),
    ] {
        let mut args = vec!["stpn", net, "--json"];
        if !with.is_empty() {
            args.extend(["--with", with]);
        }
        let out = vigie(&args);
        assert!(out.status.success(), "{}", said(&out));
        let mut child = Command::new(python())
            .arg(repo().join("tests/peers/stpn_check.py"))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("python runs");
        child.stdin.take().unwrap().write_all(&out.stdout).unwrap();
        let checked = child.wait_with_output().unwrap();
        let text = said(&checked);
        assert!(checked.status.success(), "{net} {with}: {text}");
        let last = text.lines().last().unwrap_or_default().to_string();
        let count: usize = last
            .split_whitespace()
            .next()
            .and_then(|n| n.parse().ok())
            .unwrap_or(0);
        assert!(
            last.ends_with("checks, 0 mismatches") && count >= at_least,
            "{net} {with}: {text}"
        );
    }
}

/// What a plant engineer reads: the MTFFs of chapter 4 and the double fault of chapter
/// 5, by variant; a flag the net does not have is refused with the net's flags.
#[test]
fn the_stpn_command_reports_the_thesis_s_figures() {
    let fip = "layouts/substation/nets/fip-refresh-promptness.ron";
    let out = vigie(&["stpn", fip, "--with", "write_loss,sync_loss"]);
    let text = said(&out);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("232 states"), "{text}");
    assert!(
        text.contains("MTFF (F,V): 20011940/199 (100562.512563) Ut"),
        "{text}"
    );
    assert!(text.contains("MTFF (V,F): 100060 Ut"), "{text}");
    assert!(text.contains("MTFF (F,F): 20000060 Ut"), "{text}");
    let out = vigie(&["stpn", fip]);
    assert!(said(&out).contains("MTFF (F,V): never"), "{}", said(&out));
    assert!(
        said(&out).contains("PU-P.t1 -> EA-C.t3: [60 Ut, 1]"),
        "{}",
        said(&out)
    );
    let sel = "layouts/substation/nets/logical-selectivity.ron";
    let out = vigie(&["stpn", sel]);
    assert!(
        said(&out)
            .contains("double fault: reached with probability 1 after 5800 Ut, lasts 1000 Ut"),
        "{}",
        said(&out)
    );
    assert!(
        said(&out).contains("6100 Ut: D1_vers_D2.t+"),
        "{}",
        said(&out)
    );
    let out = vigie(&["stpn", sel, "--with", "period_50ms"]);
    assert!(
        said(&out).contains("double fault: never reached"),
        "{}",
        said(&out)
    );
    let out = vigie(&["stpn", sel, "--with", "period_20ms"]);
    assert!(!out.status.success());
    assert!(
        said(&out).contains(
            "`period_20ms` is not a flag of the net (its flags: period_50ms, late_onset)"
        ),
        "{}",
        said(&out)
    );
}
