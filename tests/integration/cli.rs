//! The command line: each command takes only its own options, enumerated options list
//! their values, an inapplicable option is an error, and `vigie` alone still opens the
//! console.

use crate::live::{TempDir, Xvfb, repo, wait_until};
use crate::vigie;
use std::process::{Command, Output, Stdio};

fn text(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr)
}

/// The console's own options.
const CONSOLE: [&str; 9] = [
    "--speed",
    "--mode",
    "--level",
    "--run-until",
    "--paused",
    "--start",
    "--variant",
    "--link",
    "--lang",
];

/// Every command, as `vigie help` lists them, with what its help must show.
#[test]
fn every_commands_help_lists_only_its_own_options() {
    let top = vigie(&["--help"]);
    assert!(top.status.success());
    let top = text(&top);
    let commands: Vec<String> = top
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|c| c != "help")
        .collect();
    assert!(commands.len() >= 15, "{commands:?}");
    for c in &commands {
        let out = vigie(&[c, "--help"]);
        assert!(out.status.success(), "{c} --help: {}", text(&out));
        let help = text(&out);
        let console = matches!(c.as_str(), "console" | "run");
        for o in CONSOLE {
            assert_eq!(
                help.contains(&format!("{o} ")) || help.contains(&format!("{o}\n")),
                console,
                "`vigie {c} --help` and {o}:\n{help}"
            );
        }
        // One way to name the plant folder: the argument or `--plant`, never both.
        let positional = help.contains("[PLANT]");
        let option = help.contains("--plant");
        assert!(!(positional && option), "{c}: {help}");
    }
    // The top level is the console: its options, and the plant as `--plant`.
    for o in CONSOLE {
        assert!(top.contains(o), "vigie --help lacks {o}");
    }
    // Nested commands have their own help.
    for (c, sub) in [
        ("campaign", "transients"),
        ("diagnose", "learn"),
        ("user", "add"),
    ] {
        let out = vigie(&[c, sub, "--help"]);
        assert!(out.status.success(), "{c} {sub}: {}", text(&out));
    }
    let transients = text(&vigie(&["campaign", "transients", "--help"]));
    assert!(transients.contains("--no-plausibility") && transients.contains("--seeds"));
    let mutations = text(&vigie(&["campaign", "mutations", "--help"]));
    assert!(
        !mutations.contains("--seeds") && !mutations.contains("--no-plausibility"),
        "{mutations}"
    );
}

/// An option of another command, or one that does not apply here, is refused with a
/// message naming it; nothing runs.
#[test]
fn inapplicable_options_are_refused() {
    for (args, says) in [
        (
            vec![
                "check",
                "--speed",
                "5",
                "--link",
                "/nonexistent",
                "layouts/sorting-station",
            ],
            "unexpected argument '--speed'",
        ),
        (
            vec!["gateway", "--mode", "training", "x.ron"],
            "unexpected argument '--mode'",
        ),
        (
            vec![
                "run",
                "layouts/sorting-station/scenarios/cs10-paper.ron",
                "--headless",
                "--speed",
                "3",
            ],
            "'--headless' cannot be used with",
        ),
        (
            vec![
                "run",
                "layouts/sorting-station/scenarios/cs10-paper.ron",
                "--trace",
                "t.csv",
            ],
            "--headless",
        ),
        (vec!["--speed", "2", "check"], "cannot be used with"),
        (
            vec!["check", "--plant", "layouts/sorting-station"],
            "unexpected argument '--plant'",
        ),
        (
            vec!["--mode", "supervisor"],
            "[possible values: production, maintenance, training]",
        ),
        (vec!["--lang", "de"], "[possible values: fr, en]"),
        (vec!["--level", "7"], "7 is not in 0..=4"),
        (
            vec!["gateway", "--log", "loud", "x.ron"],
            "possible values: error, warn, info, debug, trace",
        ),
        (
            vec!["user", "add", "ann", "--role", "boss"],
            "possible values: operator, maintenance, trainer, administrator",
        ),
        (vec!["diagnose", "learn"], "<TRACES>"),
    ] {
        let out = vigie(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", text(&out));
        assert!(text(&out).contains(says), "{args:?}: {}", text(&out));
    }
}

/// Completions and manual pages come from the same definitions.
#[test]
fn completions_and_manual_pages() {
    let out = vigie(&["completions", "bash"]);
    assert!(out.status.success());
    let script = String::from_utf8_lossy(&out.stdout);
    assert!(
        script.contains("_vigie") && script.contains("gateway-bench"),
        "{script}"
    );
    let dir = TempDir::new("man");
    let out = vigie(&["man", "--out", dir.0.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out));
    let check = std::fs::read_to_string(dir.0.join("vigie-check.1")).expect("vigie-check.1");
    assert!(check.contains(".TH vigie-check"), "{check}");
    assert!(dir.0.join("vigie-campaign-transients.1").is_file());
    let top = std::fs::read_to_string(dir.0.join("vigie.1")).unwrap();
    assert!(top.contains("\\-\\-speed"), "{top}");
}

/// `vigie` with no argument opens the console: a real window on Xvfb, whose first
/// journal entry (the session) reaches the historian of its data folder.
#[test]
fn vigie_alone_opens_the_console() {
    let x = Xvfb::start();
    let dir = TempDir::new("console-alone");
    let data = dir.0.join("data");
    let mut console = Command::new(env!("CARGO_BIN_EXE_vigie"))
        .current_dir(repo())
        .env("DISPLAY", &x.display)
        .env("VIGIE_DATA_DIR", &data)
        .env("VIGIE_LANG", "en")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("the console starts");
    wait_until("the console's session entry", || {
        crate::historian_journal(&data).contains("console opened on Reference program")
    });
    // Its window is on the display (xwininfo, x11-utils).
    wait_until("the console's window", || {
        Command::new("xwininfo")
            .args(["-root", "-tree"])
            .env("DISPLAY", &x.display)
            .output()
            .map(|o| String::from_utf8_lossy(&o.stdout).contains("\"Vigie"))
            .unwrap_or_else(|e| {
                panic!("cannot run xwininfo (scripts/test.sh installs x11-utils): {e}")
            })
    });
    assert!(
        console.try_wait().unwrap().is_none(),
        "the console is running"
    );
    console.kill().unwrap();
    console.wait().unwrap();
}

/// `vigie explain` prints a code's page of the catalogue, one of each family; an
/// unknown code is an error that says where the codes are.
#[test]
fn explain_prints_a_codes_page() {
    for (code, title) in [
        ("V0301", "# V0301: "),
        ("v0701", "# V0701: "),
        ("X101", "# X101: "),
        ("T003", "# T003: "),
    ] {
        let out = vigie(&["explain", code]);
        assert!(out.status.success(), "{code}: {}", text(&out));
        let page = String::from_utf8_lossy(&out.stdout);
        assert!(page.starts_with(title), "{code}: {page}");
    }
    let out = vigie(&["explain", "V9999"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out).contains("no code `V9999` in the catalogue"),
        "{}",
        text(&out)
    );
}

/// The PLC's program leaves as PLCopen XML and comes back: `vigie program export` writes
/// the paper's erroneous variant E01, a scenario runs it from that file with the same
/// trips, boxes and hazards as from the error library, `vigie program import` reads it
/// back, and a broken file is refused with its line and column.
#[test]
fn a_program_exported_as_plcopen_runs_back_the_same() {
    let dir = TempDir::new("plcopen");
    let xml = dir.0.join("e01.xml");
    let out = vigie(&[
        "program",
        "export",
        "layouts/sorting-station",
        "--variant",
        "E01",
        "--out",
        xml.to_str().expect("utf-8"),
    ]);
    assert!(out.status.success(), "{}", text(&out));
    let written = std::fs::read_to_string(&xml).expect("written");
    assert!(
        written.contains("<SFC>") && written.contains("tc6_0201"),
        "{written}"
    );
    // The same scenario, its program read from the PLCopen file.
    let original = repo().join("layouts/sorting-station/scenarios/cs10-paper.ron");
    let text_of = std::fs::read_to_string(&original).expect("scenario");
    let plant = repo().join("layouts/sorting-station");
    let copy = text_of
        .replace(
            "Scenario(\n",
            &format!("Scenario(\n    plant: {:?},\n", plant.display().to_string()),
        )
        .replace("program: Error(\"E01\")", "program: File(\"e01.xml\")");
    assert_ne!(copy, text_of);
    let scenario = dir.0.join("cs10-from-plcopen.ron");
    std::fs::write(&scenario, copy).expect("writes");
    let report = |path: &std::path::Path| -> serde_json::Value {
        let out = vigie(&[
            "run",
            path.to_str().expect("utf-8"),
            "--headless",
            "--no-timing",
        ]);
        assert!(out.status.success(), "{}", text(&out));
        serde_json::from_slice(&out.stdout).expect("JSON report")
    };
    let (a, b) = (report(&original), report(&scenario));
    for key in ["trips", "boxes", "hazards", "cycles"] {
        assert_eq!(a[key], b[key], "{key}");
    }
    assert_eq!(a["trips"][0]["constraints"][0], "CSs10");
    // Read back: the summary names the program's charts.
    let out = vigie(&[
        "program",
        "import",
        "layouts/sorting-station",
        "--file",
        xml.to_str().expect("utf-8"),
    ]);
    assert!(out.status.success(), "{}", text(&out));
    assert!(text(&out).contains("3 charts"), "{}", text(&out));
    // A connection to an element that does not exist: refused, with where.
    let broken = dir.0.join("broken.xml");
    let mangled = written.replacen("refLocalId=\"1\"", "refLocalId=\"999\"", 1);
    std::fs::write(&broken, &mangled).expect("writes");
    let out = vigie(&[
        "program",
        "import",
        "layouts/sorting-station",
        "--file",
        broken.to_str().expect("utf-8"),
    ]);
    assert!(!out.status.success());
    let line = mangled
        .lines()
        .position(|l| l.contains("refLocalId=\"999\""))
        .expect("mangled")
        + 1;
    let said = text(&out);
    assert!(
        said.contains(&format!("broken.xml:{line}:")) && said.contains("V1206"),
        "{said}"
    );
}

/// `vigie bus FILE`: the substation's FIP bus (Table 3.2) reported, with what the
/// deadlines leave the live link; a bus that cannot keep a deadline fails, naming the
/// file and line.
#[test]
fn the_bus_command_reports_the_scan_table_and_refuses_a_deadline_it_cannot_keep() {
    let out = vigie(&["bus", "layouts/substation/bus.ron"]);
    assert!(out.status.success(), "{}", text(&out));
    let report = text(&out);
    for line in [
        "µC 25000 µs, macro-cycle 50000 µs (2 µC), TMAC 1000 ns",
        "DefDep_D1: every 50000 µs (phase 0), TE 178.000 µs, age 77.000..50077.000 µs, deadline 100000 µs; 49 ms of its deadline left for def1_D2 on the link",
    ] {
        assert!(report.contains(line), "{line}\n{report}");
    }
    let json = vigie(&["bus", "layouts/substation/bus.ron", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&json.stdout).expect("JSON");
    assert_eq!(v["variables"][1]["worst_age_ns"], 50_077_000);
    let dir = TempDir::new("bus-cli");
    let tight = dir.0.join("bus.ron");
    std::fs::write(
        &tight,
        "Bus(bit_rate: 1000000, turnaround_us: 20, variables: [\n  (name: \"v\", period_us: 50000, bytes: 2, deadline_us: 50000, signals: [\"def1_D2\"]),\n])",
    )
    .expect("writes");
    let out = vigie(&["bus", tight.to_str().expect("utf-8")]);
    assert!(!out.status.success());
    let says = text(&out);
    assert!(
        says.contains("bus.ron:2:") && says.contains("V1305"),
        "{says}"
    );
}

/// `vigie stpn NET --failed PLACE`: the producer's write loss of seed 002's chapter 4
/// (p = 0.005 per 500 Ut cycle), its mean time to the first loss exact; an unknown
/// failure place is refused.
#[test]
fn the_stpn_command_gives_the_exact_mttf_of_the_write_loss() {
    let net = "layouts/substation/nets/producer-write-loss.ron";
    let out = vigie(&["stpn", net, "--failed", "lost"]);
    assert!(out.status.success(), "{}", text(&out));
    let report = text(&out);
    assert!(report.contains("5 states, 6 arcs"), "{report}");
    assert!(report.contains("MTFF to `lost`: 99580"), "{report}");
    // The abstract view on the computing states and the loss: the early draw (state 0)
    // loses the tie half the time, 80 Ut into the cycle.
    let out = vigie(&["stpn", net, "--observe", "calcul,lost"]);
    assert!(
        text(&out).contains("0 -> 3: [80, 1/2 (0.500000)]"),
        "{}",
        text(&out)
    );
    let out = vigie(&["stpn", net, "--failed", "nowhere"]);
    assert!(!out.status.success());
    assert!(
        text(&out).contains("`nowhere` is not a place"),
        "{}",
        text(&out)
    );
}
