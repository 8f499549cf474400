//! IEC 61131-3 conformance of imported programs, on worked examples written as a PLC
//! tool writes them (inline ST conditions, divergences, jumps, action blocks), run one
//! scan at a time: one test per action qualifier and per divergence kind, the SFC's
//! evolution rules, LD rungs, and ST bodies against the project's ST interpreter.

use super::super::import;
use super::Open;
use crate::diag::codes;
use crate::plant::Plant;
use std::path::Path;

/// Inputs a, b, d of the single conveyor, outputs P and CV.
fn plant() -> Plant {
    Plant::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/single-conveyor/plant.ron"))
        .expect("plant")
}

const VARS: &str = r#"<variable name="a"><type><BOOL/></type></variable>
<variable name="b"><type><BOOL/></type></variable>
<variable name="d"><type><BOOL/></type></variable>
<variable name="W"><type><BOOL/></type></variable>
<variable name="K"><type><BOOL/></type></variable>"#;

fn project(pous: &str) -> String {
    format!(
        r#"<?xml version="1.0" encoding="utf-8"?>
<project xmlns="http://www.plcopen.org/xml/tc6_0201" xmlns:xhtml="http://www.w3.org/1999/xhtml">
  <fileHeader companyName="t" productName="t" productVersion="1" creationDateTime="2026-01-01T00:00:00"/>
  <contentHeader name="conformance"><coordinateInfo><fbd><scaling x="1" y="1"/></fbd><ld><scaling x="1" y="1"/></ld><sfc><scaling x="1" y="1"/></sfc></coordinateInfo></contentHeader>
  <types><dataTypes/><pous>
{pous}
  </pous></types>
</project>"#
    )
}

fn sfc(body: &str) -> String {
    project(&format!(
        r#"<pou name="main" pouType="program"><interface><localVars>{VARS}</localVars></interface>
<body><SFC>
{body}
</SFC></body></pou>"#
    ))
}

fn step(id: u32, name: &str, initial: bool, from: &[u32]) -> String {
    let conn: String = from
        .iter()
        .map(|r| format!(r#"<connection refLocalId="{r}"/>"#))
        .collect();
    let conn = if from.is_empty() {
        String::new()
    } else {
        format!("<connectionPointIn>{conn}</connectionPointIn>")
    };
    format!(
        r#"<step localId="{id}" name="{name}" initialStep="{initial}"><position x="0" y="{}"/>{conn}<connectionPointOut formalParameter=""/></step>"#,
        id * 10
    )
}

fn trans_at(id: u32, from: u32, cond: &str, x: u32) -> String {
    format!(
        r#"<transition localId="{id}"><position x="{x}" y="{}"/><connectionPointIn><connection refLocalId="{from}"/></connectionPointIn><condition><inline name=""><ST><xhtml:p><![CDATA[{cond}]]></xhtml:p></ST></inline></condition></transition>"#,
        id * 10
    )
}

fn trans(id: u32, from: u32, cond: &str) -> String {
    trans_at(id, from, cond, 0)
}

fn actions(id: u32, step: u32, list: &[(&str, Option<&str>, &str)]) -> String {
    let acts: String = list
        .iter()
        .map(|(q, d, v)| {
            let d = d.map(|d| format!(r#" duration="{d}""#)).unwrap_or_default();
            format!(r#"<action localId="0" qualifier="{q}"{d}><reference name="{v}"/></action>"#)
        })
        .collect();
    format!(
        r#"<actionBlock localId="{id}"><position x="100" y="0"/><connectionPointIn><connection refLocalId="{step}"/></connectionPointIn>{acts}</actionBlock>"#
    )
}

fn open(xml: &str) -> Open {
    Open::new(xml, Path::new("t.xml"), plant())
}

/// A two-step loop S0 -(a)-> S1 -(b)-> S0, with `acts` on S1.
fn loop_with(acts: &[(&str, Option<&str>, &str)]) -> String {
    sfc(&[
        step(1, "S0", true, &[4]),
        trans(2, 1, "a"),
        step(3, "S1", false, &[2]),
        trans(4, 3, "b"),
        actions(5, 3, acts),
    ]
    .concat())
}

/// W over the scans of `inputs`.
fn trace(xml: &str, inputs: &[&[&str]], var: &str) -> Vec<bool> {
    let mut o = open(xml);
    inputs.iter().map(|i| o.scan(i).v(var)).collect()
}

#[test]
fn qualifier_n_holds_while_the_step_is_active_and_not_after() {
    let xml = loop_with(&[("N", None, "W")]);
    let got = trace(&xml, &[&[], &["a"], &[], &[], &["b"], &[]], "W");
    assert_eq!(got, [false, true, true, true, false, false]);
}

#[test]
fn qualifier_s_stores_until_an_r_and_reset_wins_in_the_same_scan() {
    // S0 -(a)-> S1 [S W] -(b)-> S2 -(a)-> S3 [R W] -(b)-> S0.
    let xml = sfc(&[
        step(1, "S0", true, &[8]),
        trans(2, 1, "a"),
        step(3, "S1", false, &[2]),
        actions(20, 3, &[("S", None, "W")]),
        trans(4, 3, "b"),
        step(5, "S2", false, &[4]),
        trans(6, 5, "a"),
        step(7, "S3", false, &[6]),
        actions(21, 7, &[("R", None, "W")]),
        trans(8, 7, "b"),
    ]
    .concat());
    let got = trace(&xml, &[&["a"], &["b"], &[], &["a"], &["b"], &[]], "W");
    assert_eq!(got, [true, true, true, false, false, false]);
    // Set and reset by two steps active together: the reset wins.
    let xml = sfc(&[
        step(1, "S0", true, &[]),
        step(2, "S1", true, &[]),
        actions(3, 1, &[("S", None, "W")]),
        actions(4, 2, &[("R", None, "W")]),
    ]
    .concat());
    assert_eq!(trace(&xml, &[&[], &[]], "W"), [false, false]);
}

#[test]
fn qualifier_r_resets_a_value_stored_by_another_step() {
    let xml = sfc(&[
        step(1, "S0", true, &[4]),
        actions(10, 1, &[("S", None, "W")]),
        trans(2, 1, "a"),
        step(3, "S1", false, &[2]),
        actions(11, 3, &[("R", None, "W")]),
        trans(4, 3, "b"),
    ]
    .concat());
    let got = trace(&xml, &[&[], &["a"], &[], &["b"]], "W");
    assert_eq!(got, [true, false, false, true]);
}

#[test]
fn qualifier_p_is_true_in_the_activation_scan_only() {
    let xml = loop_with(&[("P", None, "W")]);
    let got = trace(&xml, &[&[], &["a"], &[], &["b"], &["a"], &["a"]], "W");
    assert_eq!(got, [false, true, false, false, true, false]);
}

#[test]
fn qualifier_l_limits_to_its_duration_and_ends_with_the_step() {
    let xml = loop_with(&[("L", Some("T#30ms"), "W")]);
    // Activated at 20 ms: true at 20, 30, 40 ms (elapsed 0, 10, 20), false from 50 ms.
    let got = trace(&xml, &[&[], &["a"], &[], &[], &[], &[]], "W");
    assert_eq!(got, [false, true, true, true, false, false]);
    // Deactivated before the time is up: false at once.
    let got = trace(&xml, &[&["a"], &["b"], &[]], "W");
    assert_eq!(got, [true, false, false]);
}

#[test]
fn qualifier_d_waits_for_its_duration_and_never_comes_if_the_step_ends_first() {
    let xml = loop_with(&[("D", Some("T#30ms"), "W")]);
    let got = trace(&xml, &[&["a"], &[], &[], &[], &[], &["b"], &[]], "W");
    assert_eq!(got, [false, false, false, true, true, false, false]);
    let got = trace(&xml, &[&["a"], &[], &["b"], &[], &[], &[]], "W");
    assert_eq!(got, [false; 6]);
}

#[test]
fn qualifiers_not_run_yet_are_refused_where_they_are() {
    for q in ["P1", "P0"] {
        let xml = loop_with(&[(q, Some("T#30ms"), "W")]);
        let err = import(&xml, Path::new("t.xml"), &plant()).expect_err(q);
        assert_eq!(
            err[0].code,
            codes::PLCOPEN_UNSUPPORTED.id,
            "{q}: {}",
            err[0]
        );
        assert!(err[0].message.contains(q), "{}", err[0]);
        let line = xml
            .lines()
            .position(|l| l.contains(&format!("qualifier=\"{q}\"")))
            .expect("line")
            + 1;
        assert_eq!(
            err[0].location.as_ref().map(|l| l.line),
            Some(line),
            "{}",
            err[0]
        );
    }
}

/// S0 resets W; S0 -(a)-> S1 with `acts` -(b)-> S0.
fn loop_resetting(acts: &[(&str, Option<&str>, &str)]) -> String {
    sfc(&[
        step(1, "S0", true, &[4]),
        actions(6, 1, &[("R", None, "W")]),
        trans(2, 1, "a"),
        step(3, "S1", false, &[2]),
        trans(4, 3, "b"),
        actions(5, 3, acts),
    ]
    .concat())
}

#[test]
fn qualifier_sd_sets_after_its_time_even_when_the_step_ended_unless_reset() {
    // Activated at 10 ms: set at 40 ms, although S1 ended at 20 ms.
    let xml = loop_with(&[("SD", Some("T#30ms"), "W")]);
    let got = trace(&xml, &[&["a"], &["b"], &[], &[], &[], &[]], "W");
    assert_eq!(got, [false, false, false, true, true, true]);
    // An R while the time runs cancels it.
    let xml = loop_resetting(&[("SD", Some("T#30ms"), "W")]);
    let got = trace(&xml, &[&["a"], &["b"], &[], &[], &[]], "W");
    assert_eq!(got, [false; 5]);
    // Set while S1 lasts, reset when S0 comes back.
    let got = trace(&xml, &[&["a"], &[], &[], &[], &["b"], &[]], "W");
    assert_eq!(got, [false, false, false, true, false, false]);
}

#[test]
fn qualifier_ds_sets_only_if_the_step_lasts_its_time() {
    let xml = loop_with(&[("DS", Some("T#30ms"), "W")]);
    let got = trace(&xml, &[&["a"], &[], &[], &[], &["b"], &[]], "W");
    assert_eq!(
        got,
        [false, false, false, true, true, true],
        "stored after S1"
    );
    let got = trace(&xml, &[&["a"], &["b"], &[], &[], &[]], "W");
    assert_eq!(got, [false; 5], "S1 too short");
}

#[test]
fn qualifier_sl_lasts_its_time_even_when_the_step_ended_unless_reset() {
    let xml = loop_with(&[("SL", Some("T#30ms"), "W")]);
    let got = trace(&xml, &[&["a"], &["b"], &[], &[], &[]], "W");
    assert_eq!(got, [true, true, true, false, false]);
    let xml = loop_resetting(&[("SL", Some("T#30ms"), "W")]);
    let got = trace(&xml, &[&["a"], &["b"], &[], &[], &[]], "W");
    assert_eq!(got, [true, false, false, false, false], "S0's R ends it");
}

/// Selection divergence: of the transitions leaving a step, only the leftmost true one
/// fires (IEC 61131-3 left-to-right precedence), then a selection convergence.
#[test]
fn selection_divergence_fires_the_leftmost_true_branch_only() {
    let body = [
        step(1, "S0", true, &[9]),
        r#"<selectionDivergence localId="2"><position x="0" y="20"/><connectionPointIn><connection refLocalId="1"/></connectionPointIn><connectionPointOut formalParameter=""/><connectionPointOut formalParameter=""/></selectionDivergence>"#.to_string(),
        trans_at(3, 2, "a", 0),
        trans_at(4, 2, "a OR b", 100),
        step(5, "L", false, &[3]),
        step(6, "R", false, &[4]),
        trans(7, 5, "d"),
        trans(8, 6, "d"),
        r#"<selectionConvergence localId="9"><position x="0" y="90"/><connectionPointIn><connection refLocalId="7"/></connectionPointIn><connectionPointIn><connection refLocalId="8"/></connectionPointIn><connectionPointOut/></selectionConvergence>"#.to_string(),
    ]
    .concat();
    let xml = sfc(&body);
    let mut o = open(&xml);
    assert_eq!(
        o.scan(&["a", "b"]).active(),
        ["L"],
        "both true: the left one only"
    );
    assert_eq!(
        o.scan(&["d"]).active(),
        ["S0"],
        "the convergence returns to S0"
    );
    assert_eq!(o.scan(&["b"]).active(), ["R"], "only the right one true");
    assert_eq!(o.scan(&["d"]).active(), ["S0"]);
}

/// Simultaneous divergence activates every branch; the simultaneous convergence fires
/// only when every branch's last step is active.
#[test]
fn simultaneous_divergence_and_convergence() {
    let body = [
        step(1, "S0", true, &[10]),
        trans(2, 1, "a"),
        r#"<simultaneousDivergence localId="3"><position x="0" y="30"/><connectionPointIn><connection refLocalId="2"/></connectionPointIn><connectionPointOut formalParameter=""/><connectionPointOut formalParameter=""/></simultaneousDivergence>"#.to_string(),
        step(4, "L1", false, &[3]),
        step(5, "R1", false, &[3]),
        trans(6, 4, "b"),
        step(7, "L2", false, &[6]),
        r#"<simultaneousConvergence localId="8"><position x="0" y="80"/><connectionPointIn><connection refLocalId="7"/></connectionPointIn><connectionPointIn><connection refLocalId="5"/></connectionPointIn><connectionPointOut/></simultaneousConvergence>"#.to_string(),
        trans(9, 8, "d"),
        step(10, "S1", false, &[9]),
    ]
    .concat();
    let mut o = open(&sfc(&body));
    assert_eq!(o.scan(&["a"]).active(), ["L1", "R1"]);
    assert_eq!(
        o.scan(&["d"]).active(),
        ["L1", "R1"],
        "L2 not reached: no convergence"
    );
    assert_eq!(o.scan(&["b"]).active(), ["R1", "L2"]);
    assert_eq!(o.scan(&["d"]).active(), ["S1"], "both branches done");
}

#[test]
fn a_jump_returns_to_its_target_step() {
    let body = [
        step(1, "S0", true, &[]),
        trans(2, 1, "a"),
        step(3, "S1", false, &[2]),
        trans(4, 3, "b"),
        r#"<jumpStep localId="5" targetName="S0"><position x="0" y="50"/><connectionPointIn><connection refLocalId="4"/></connectionPointIn></jumpStep>"#.to_string(),
    ]
    .concat();
    let mut o = open(&sfc(&body));
    assert_eq!(o.scan(&["a"]).active(), ["S1"]);
    assert_eq!(o.scan(&["b"]).active(), ["S0"]);
}

/// One evolution per scan: a transition enabled by the new situation waits for the next
/// scan, even when its condition is already true (no search for stability).
#[test]
fn one_evolution_per_scan() {
    let body = [
        step(1, "S0", true, &[]),
        trans(2, 1, "a"),
        step(3, "S1", false, &[2]),
        trans(4, 3, "a"),
        step(5, "S2", false, &[4]),
    ]
    .concat();
    let mut o = open(&sfc(&body));
    assert_eq!(o.scan(&["a"]).active(), ["S1"]);
    assert_eq!(o.scan(&["a"]).active(), ["S2"]);
}

/// A step's time `S.T` against a duration, and a transition reading the value an action
/// gave in the previous scan.
#[test]
fn step_time_and_previous_scan_values_in_conditions() {
    let body = [
        step(1, "S0", true, &[4]),
        trans(2, 1, "a"),
        step(3, "S1", false, &[2]),
        actions(6, 3, &[("N", None, "W")]),
        trans(4, 3, "S1.T >= T#30ms AND W"),
    ]
    .concat();
    let mut o = open(&sfc(&body));
    o.scan(&["a"]);
    assert_eq!(o.scan(&[]).active(), ["S1"]);
    assert_eq!(o.scan(&[]).active(), ["S1"]);
    assert_eq!(o.scan(&[]).active(), ["S0"], "30 ms after the activation");
    // `>` is one millisecond later: with 10 ms scans, one scan later.
    let xml = sfc(&[
        step(1, "S0", true, &[4]),
        trans(2, 1, "a"),
        step(3, "S1", false, &[2]),
        trans(4, 3, "S1.T > T#30ms"),
    ]
    .concat());
    let mut o = open(&xml);
    o.scan(&["a"]);
    let n = (0..10)
        .take_while(|_| o.scan(&[]).active() == ["S1"])
        .count();
    assert_eq!(n, 3);
}

fn ld(body: &str) -> String {
    project(&format!(
        r#"<pou name="rungs" pouType="program"><interface><localVars>{VARS}
<variable name="trig"><type><derived name="R_TRIG"/></type></variable></localVars>
<outputVars><variable name="Q" address="%QX0.1"><type><BOOL/></type></variable></outputVars></interface>
<body><LD>
<leftPowerRail localId="1"><position x="0" y="0"/><connectionPointOut formalParameter=""/></leftPowerRail>
{body}
</LD></body></pou>"#
    ))
}

fn contact(id: u32, from: u32, var: &str, extra: &str, y: u32) -> String {
    format!(
        r#"<contact localId="{id}"{extra}><position x="50" y="{y}"/><connectionPointIn><connection refLocalId="{from}"/></connectionPointIn><variable>{var}</variable></contact>"#
    )
}

fn coil(id: u32, from: &[u32], var: &str, extra: &str, y: u32) -> String {
    let conn: String = from
        .iter()
        .map(|r| format!(r#"<connection refLocalId="{r}"/>"#))
        .collect();
    format!(
        r#"<coil localId="{id}"{extra}><position x="200" y="{y}"/><connectionPointIn>{conn}</connectionPointIn><variable>{var}</variable></coil>"#
    )
}

/// LD: a seal-in rung (start a, stop b), the output at %QX0.1 (the conveyor CV), an edge
/// contact, set and reset coils, and a wired OR.
#[test]
fn ladder_rungs_as_a_plc_scans_them() {
    let body = [
        // W := (a OR W) AND NOT b  (seal-in: W read before its coil is the last scan's)
        contact(10, 1, "a", "", 10),
        contact(11, 1, "W", "", 20),
        contact(12, 10, "b", r#" negated="true""#, 10),
        r#"<contact localId="13" negated="true"><position x="60" y="20"/><connectionPointIn><connection refLocalId="11"/></connectionPointIn><variable>b</variable></contact>"#.to_string(),
        coil(14, &[12, 13], "W", "", 10),
        // Q := W
        contact(20, 1, "W", "", 40),
        coil(21, &[20], "Q", "", 40),
        // K set on the rising edge of d, reset by b.
        contact(30, 1, "d", r#" edge="rising""#, 60),
        coil(31, &[30], "K", r#" storage="set""#, 60),
        contact(32, 1, "b", "", 70),
        coil(33, &[32], "K", r#" storage="reset""#, 70),
    ]
    .concat();
    let mut o = open(&ld(&body));
    let mut step = |i: &[&str]| {
        o.scan(i);
        (o.v("W"), o.v("CV"), o.v("K"))
    };
    assert_eq!(step(&[]), (false, false, false));
    assert_eq!(step(&["a"]), (true, true, false), "started");
    assert_eq!(step(&[]), (true, true, false), "sealed in");
    assert_eq!(step(&["d"]), (true, true, true), "rising edge of d sets K");
    assert_eq!(step(&["d"]), (true, true, true), "K stays set with d held");
    assert_eq!(
        step(&["b", "d"]),
        (false, false, false),
        "b stops W and resets K"
    );
    assert_eq!(step(&["d"]), (false, false, false), "d held: no new edge");
}

/// `xml` is refused with a problem of `code` whose message contains `needle`, placed
/// on the first line that contains `marker`.
fn refused_at(xml: &str, code: &str, needle: &str, marker: &str) {
    let err = import(xml, Path::new("t.xml"), &plant()).expect_err(needle);
    let p = err
        .iter()
        .find(|p| p.message.contains(needle))
        .unwrap_or_else(|| panic!("{needle}: {}", crate::diag::render(&err)));
    assert_eq!(p.code, code, "{p}");
    let line = xml
        .lines()
        .position(|l| l.contains(marker))
        .expect("marker")
        + 1;
    assert_eq!(p.location.as_ref().map(|l| l.line), Some(line), "{p}");
}

#[test]
fn unsupported_and_malformed_elements_are_named_with_their_line() {
    let plant = plant();
    let check = refused_at;
    // An inline action body.
    let xml = sfc(&[
        step(1, "S0", true, &[]),
        r#"
<actionBlock localId="2"><position x="0" y="0"/><connectionPointIn><connection refLocalId="1"/></connectionPointIn><action localId="0" qualifier="N"><inline><ST><xhtml:p>W := TRUE;</xhtml:p></ST></inline></action></actionBlock>"#.to_string(),
    ]
    .concat());
    check(
        &xml,
        codes::PLCOPEN_UNSUPPORTED.id,
        "inline action body",
        "<inline><ST>",
    );
    // A dangling connection.
    let xml = sfc(&[
        step(1, "S0", true, &[]),
        "\n".into(),
        trans(2, 7, "a"),
        step(3, "S1", false, &[2]),
    ]
    .concat());
    check(
        &xml,
        codes::PLCOPEN_SFC_GRAPH.id,
        "localId 7",
        "<transition localId=\"2\"",
    );
    // An INT variable used, and arithmetic.
    let xml = project(&format!(
        r#"<pou name="main" pouType="program"><interface><localVars>{VARS}
<variable name="n"><type><INT/></type></variable></localVars></interface>
<body><ST><xhtml:p><![CDATA[W := a;
IF n THEN K := b; END_IF;]]></xhtml:p></ST></body></pou>"#
    ));
    check(&xml, codes::PLCOPEN_UNSUPPORTED.id, "type INT", "IF n THEN");
    // The same laid out as the tools write it (`<xhtml:p>` on a line of its own, the
    // text from the line after the CDATA): the layout before the text shifts no line.
    let xml = project(&format!(
        r#"<pou name="main" pouType="program"><interface><localVars>{VARS}
<variable name="n"><type><INT/></type></variable></localVars></interface>
<body>
  <ST>
    <xhtml:p><![CDATA[
W := a;
IF n THEN K := b; END_IF;
]]></xhtml:p>
  </ST>
</body></pou>"#
    ));
    check(&xml, codes::PLCOPEN_UNSUPPORTED.id, "type INT", "IF n THEN");
    // An IL body.
    let xml = project(
        r#"<pou name="main" pouType="program"><interface/>
<body><IL><xhtml:p>LD a</xhtml:p></IL></body></pou>"#,
    );
    check(&xml, codes::PLCOPEN_UNSUPPORTED.id, "IL", "<IL>");
    // Not well-formed.
    let xml = "<project>\n  <types>\n</project>";
    check(
        xml,
        codes::PLCOPEN_XML_INVALID.id,
        "well-formed",
        "</project>",
    );
    // An unknown variable in a condition, at its column.
    let xml = sfc(&[
        step(1, "S0", true, &[]),
        "\n".into(),
        trans(2, 1, "a AND zz"),
        step(3, "S1", false, &[2]),
    ]
    .concat());
    let err = import(&xml, Path::new("t.xml"), &plant).expect_err("zz");
    let loc = err[0].location.clone().expect("located");
    let line = xml.lines().nth(loc.line - 1).expect("line");
    assert_eq!(
        line.find("zz").map(|c| c + 1),
        Some(loc.column),
        "{}",
        err[0]
    );
    // A located variable at an address the plant does not have.
    let xml = project(
        r#"<pou name="main" pouType="program"><interface><localVars>
<variable name="Y" address="%QX9.7"><type><BOOL/></type></variable></localVars></interface>
<body><ST><xhtml:p>Y := TRUE;</xhtml:p></ST></body></pou>"#,
    );
    check(&xml, codes::PLCOPEN_BINDING.id, "coil 79", "%QX9.7");
}

mod st_against_interp {
    //! ST bodies against the project's ST interpreter (`crate::export::interp`): random
    //! statement lists of assignments and IFs over inputs and memories, read before and
    //! after their writes, scan after scan.
    use super::*;
    use crate::export::interp::{self, Val};
    use proptest::prelude::*;

    const INPUTS: [&str; 3] = ["a", "b", "d"];
    const MEMS: [&str; 2] = ["W", "K"];

    fn expr() -> impl Strategy<Value = String> {
        let leaf = prop_oneof![
            prop::sample::select(vec!["a", "b", "d", "W", "K", "TRUE", "FALSE"])
                .prop_map(str::to_string),
        ];
        leaf.prop_recursive(3, 12, 2, |inner| {
            prop_oneof![
                inner.clone().prop_map(|x| format!("NOT {x}")),
                (
                    inner.clone(),
                    inner.clone(),
                    prop::sample::select(vec!["AND", "OR", "XOR", "=", "<>"])
                )
                    .prop_map(|(x, y, op)| format!("({x} {op} {y})")),
            ]
        })
    }

    fn stmt() -> impl Strategy<Value = String> {
        let assign =
            (prop::sample::select(MEMS.to_vec()), expr()).prop_map(|(m, e)| format!("{m} := {e};"));
        assign.prop_recursive(2, 8, 3, |inner| {
            (
                expr(),
                prop::collection::vec(inner.clone(), 1..3),
                prop::collection::vec(inner, 0..2),
            )
                .prop_map(|(c, then, other)| {
                    let other = if other.is_empty() {
                        String::new()
                    } else {
                        format!(" ELSE {}", other.concat())
                    };
                    format!("IF {c} THEN {}{other} END_IF;", then.concat())
                })
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]
        #[test]
        fn st_bodies_run_as_the_st_interpreter_runs_them(
            body in prop::collection::vec(stmt(), 1..5),
            scans in prop::collection::vec(prop::collection::vec(any::<bool>(), 3), 1..8),
        ) {
            let body = body.join("\n");
            let xml = project(&format!(
                r#"<pou name="main" pouType="program"><interface><localVars>{VARS}</localVars></interface>
    <body><ST><xhtml:p><![CDATA[{body}]]></xhtml:p></ST></body></pou>"#
            ));
            let text = format!(
                "PROGRAM MAIN\nVAR\n a : BOOL;\n b : BOOL;\n d : BOOL;\n W : BOOL;\n K : BOOL;\nEND_VAR\n{body}\nEND_PROGRAM\n"
            );
            let unit = interp::parse(&text).map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
            let mut reference = interp::Machine::new(unit, "MAIN").map_err(|e| TestCaseError::fail(e.to_string()))?;
            let mut o = open(&xml);
            for inputs in &scans {
                let on: Vec<&str> = INPUTS.iter().zip(inputs).filter(|(_, v)| **v).map(|(n, _)| *n).collect();
                for (n, v) in INPUTS.iter().zip(inputs) {
                    reference.set(n, Val::Bool(*v)).map_err(|e| TestCaseError::fail(e.to_string()))?;
                }
                reference.scan().map_err(|e| TestCaseError::fail(e.to_string()))?;
                o.scan(&on);
                for m in MEMS {
                    let want = reference.get(m).map_err(|e| TestCaseError::fail(e.to_string()))?;
                    prop_assert_eq!(Val::Bool(o.v(m)), want, "{} after inputs {:?}\n{}", m, on, body);
                }
            }
        }
    }
}

/// `W` over the scans of `inputs` for an ST body calling a standard timer `t` of `ty`.
fn timer_trace(ty: &str, inputs: &[&[&str]]) -> Vec<bool> {
    let xml = project(&format!(
        r#"<pou name="main" pouType="program"><interface><localVars>{VARS}
<variable name="t"><type><derived name="{ty}"/></type></variable></localVars></interface>
<body><ST><xhtml:p><![CDATA[t(IN := a, PT := T#30ms);
W := t.Q;]]></xhtml:p></ST></body></pou>"#
    ));
    trace(&xml, inputs, "W")
}

#[test]
fn ton_rises_after_its_time_and_falls_with_its_input() {
    let got = timer_trace(
        "TON",
        &[&["a"], &["a"], &["a"], &["a"], &["a"], &[], &["a"], &["a"]],
    );
    // Input from 10 ms: Q at 40 ms (30 ms later); input off at 60 ms: Q off; on again
    // at 70 ms: the time starts again.
    assert_eq!(got, [false, false, false, true, true, false, false, false]);
}

#[test]
fn tof_holds_its_time_after_its_input_falls() {
    // Input at 20 ms only: Q from 20 ms, and 30 ms after the fall at 30 ms (30, 40,
    // 50 ms), off at 60 ms.
    let got = timer_trace(
        "TOF",
        &[&[], &["a"], &[], &[], &[], &[], &["a"], &[], &["a"]],
    );
    assert_eq!(
        got,
        [false, true, true, true, true, false, true, true, true]
    );
}

#[test]
fn tp_gives_one_pulse_per_rising_edge_of_its_time() {
    // A rising edge starts a pulse of 30 ms whatever the input does; a new pulse needs
    // a new rising edge after the pulse.
    let got = timer_trace(
        "TP",
        &[
            &["a"],
            &[],
            &["a"],
            &["a"],
            &["a"],
            &["a"],
            &[],
            &["a"],
            &["a"],
        ],
    );
    assert_eq!(
        got,
        [true, true, true, false, false, false, false, true, true]
    );
}

/// An ST body calling a standard counter `c` of `ty` (`CU`/`R` or `CD`/`LD` from `a`
/// and `b`, PV `pv`), `W` its Q.
fn counter_xml(ty: &str, pv: &str, extra: &str) -> String {
    let (count, reset) = if ty == "CTU" {
        ("CU", "R")
    } else {
        ("CD", "LD")
    };
    project(&format!(
        r#"<pou name="main" pouType="program"><interface><localVars>{VARS}
<variable name="c"><type><derived name="{ty}"/></type></variable>{extra}</localVars></interface>
<body><ST><xhtml:p><![CDATA[c({count} := a, {reset} := b, PV := {pv});
W := c.Q;]]></xhtml:p></ST></body></pou>"#
    ))
}

#[test]
fn ctu_counts_rising_edges_up_to_its_preset_and_r_clears_it() {
    let xml = counter_xml("CTU", "3", "");
    // Edges at scans 1, 3 (held over 4: one edge), 6: Q from the third. R at scan 8
    // clears (and wins over the edge of the same scan); three new edges are needed.
    let got = trace(
        &xml,
        &[
            &["a"],
            &[],
            &["a"],
            &["a"],
            &[],
            &["a"],
            &[],
            &["a", "b"],
            &[],
            &["a"],
            &[],
            &["a"],
            &[],
            &["a"],
        ],
        "W",
    );
    let want = [
        false, false, false, false, false, true, true, false, false, false, false, false, false,
        true,
    ];
    assert_eq!(got, want);
}

#[test]
fn ctd_counts_down_from_its_loaded_preset_and_is_true_at_zero() {
    // CV starts at 0: Q is true from the first call. LD loads PV = 2; two edges of
    // CD bring it back to 0.
    let xml = counter_xml(
        "CTD",
        "N",
        r#"<variable name="N"><type><INT/></type><initialValue><simpleValue value="2"/></initialValue></variable>"#,
    );
    let got = trace(
        &xml,
        &[&[], &["b"], &[], &["a"], &[], &["a"], &["a"], &[]],
        "W",
    );
    assert_eq!(got, [true, false, false, false, false, true, true, true]);
}

/// A program with counters reads back the same after export and import, and runs the
/// same, scan by scan.
#[test]
fn counters_read_back_the_same_after_export_and_import() {
    let plant = plant();
    for ty in ["CTU", "CTD"] {
        let xml = counter_xml(ty, "2", "");
        let p1 = import(&xml, Path::new("t.xml"), &plant).expect("imports");
        assert_eq!(p1.counters.len(), 1, "{p1:?}");
        let xml2 = crate::plcopen::export(&p1, &plant, Path::new("t.ron")).expect("exports");
        assert!(
            xml2.contains(&format!("<derived name=\"{ty}\"/>")),
            "{xml2}"
        );
        let p2 = import(&xml2, Path::new("t2.xml"), &plant).expect("imports again");
        let unplaced = |p: &crate::control::Program| crate::control::Program {
            places: std::collections::BTreeMap::new(),
            ..p.clone()
        };
        assert_eq!(unplaced(&p1), unplaced(&p2), "{xml2}");
        let scans: &[&[&str]] = &[
            &["a"],
            &[],
            &["b"],
            &["a"],
            &[],
            &["a"],
            &["a", "b"],
            &["a"],
            &[],
            &["a"],
        ];
        assert_eq!(trace(&xml, scans, "W"), trace(&xml2, scans, "W"), "{ty}");
    }
}

#[test]
fn counters_refuse_what_they_cannot_run_where_it_is() {
    let check = |xml: &str, needle: &str, marker: &str| {
        refused_at(xml, codes::PLCOPEN_UNSUPPORTED.id, needle, marker);
    };
    // CV is an INT.
    let xml = project(&format!(
        r#"<pou name="main" pouType="program"><interface><localVars>{VARS}
<variable name="c"><type><derived name="CTU"/></type></variable></localVars></interface>
<body><ST><xhtml:p><![CDATA[c(CU := a, PV := 2);
W := c.CV;]]></xhtml:p></ST></body></pou>"#
    ));
    check(&xml, "`.CV` is an INT", "W := c.CV");
    // PV from an INT without a constant value.
    let xml = counter_xml(
        "CTU",
        "n",
        r#"<variable name="n"><type><INT/></type></variable>"#,
    );
    check(&xml, "PV is `n`, not a constant", "c(CU");
    // PV outside INT.
    let xml = counter_xml("CTU", "40000", "");
    check(&xml, "outside INT", "c(CU");
    // A counter called under IF.
    let xml = project(&format!(
        r#"<pou name="main" pouType="program"><interface><localVars>{VARS}
<variable name="c"><type><derived name="CTD"/></type></variable></localVars></interface>
<body><ST><xhtml:p><![CDATA[IF b THEN
c(CD := a, PV := 2); END_IF;
W := c.Q;]]></xhtml:p></ST></body></pou>"#
    ));
    check(&xml, "called under a condition", "c(CD");
}
