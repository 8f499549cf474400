//! French and English (issue 19): the console's texts are Fluent messages
//! (`assets/i18n/<lang>.ftl`, built in), switched at run time; a plant folder may add
//! its own texts in `i18n/<lang>.ftl` (the descriptions of its signals, e.g.
//! `signal-C4 = …`), read after the built-in ones.
//!
//! A message missing in the language shown falls back to English, and a message
//! missing in English shows its id (a test checks that every id the console uses is in
//! both files, and that both files hold the same ids).

use fluent_bundle::concurrent::FluentBundle;
use fluent_bundle::{FluentArgs, FluentResource, FluentValue};
use std::path::{Path, PathBuf};

/// A language of the console.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Lang {
    /// English.
    #[default]
    En,
    /// French.
    Fr,
}

impl Lang {
    /// Every language, in the order of the switch.
    pub const ALL: [Lang; 2] = [Lang::Fr, Lang::En];

    /// `en`, `fr`.
    pub fn code(self) -> &'static str {
        match self {
            Self::En => "en",
            Self::Fr => "fr",
        }
    }

    /// `EN`, `FR` (the switch's labels).
    pub fn label(self) -> &'static str {
        match self {
            Self::En => "EN",
            Self::Fr => "FR",
        }
    }

    /// `fr`, `fr_FR.UTF-8`, `fr-CA`, `en_GB`…: the language of a locale name.
    pub fn parse(s: &str) -> Option<Self> {
        let lang = s
            .split(['_', '-', '.', '@'])
            .next()
            .unwrap_or_default()
            .to_ascii_lowercase();
        match lang.as_str() {
            "fr" => Some(Self::Fr),
            "en" => Some(Self::En),
            _ => None,
        }
    }

    /// The system's language: `VIGIE_LANG`, else `LC_ALL`, `LC_MESSAGES`, `LANG`
    /// (POSIX order); English when none names a language the console speaks.
    pub fn from_env() -> Self {
        ["VIGIE_LANG", "LC_ALL", "LC_MESSAGES", "LANG"]
            .iter()
            .filter_map(|v| std::env::var(v).ok())
            .find(|v| !v.is_empty())
            .and_then(|v| Self::parse(&v))
            .unwrap_or_default()
    }

    fn source(self) -> &'static str {
        match self {
            Self::En => include_str!("../../assets/i18n/en.ftl"),
            Self::Fr => include_str!("../../assets/i18n/fr.ftl"),
        }
    }

    fn langid(self) -> unic_langid::LanguageIdentifier {
        unic_langid::LanguageIdentifier::from_bytes(self.code().as_bytes()).unwrap_or_default()
    }
}

/// The explanation items in French, by code (`explain-X201`…); in English the console
/// shows the text the core wrote.
const FR_EXPLAIN: &str = include_str!("../../assets/i18n/fr-explain.ftl");

/// Fields of explanation items that hold comma-separated lists.
const LIST_FIELDS: [&str; 13] = [
    "constraints",
    "outputs",
    "elements",
    "values",
    "actuators",
    "observers",
    "signals",
    "steps",
    "transitions",
    "activated",
    "driven",
    "reasons",
    "exits",
];

/// Fields of explanation items that are numbers (Fluent selects on them).
const NUMBER_FIELDS: [&str; 4] = ["time_ms", "after_ms", "ms_before", "horizon_ms"];

/// A text file that does not parse.
#[derive(Debug, thiserror::Error)]
#[error("{}:{line}:{column}: {message}", file.display())]
pub struct I18nError {
    /// The file.
    pub file: PathBuf,
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

fn parse(text: &str, file: &Path) -> Result<FluentResource, I18nError> {
    FluentResource::try_new(text.to_string()).map_err(|(_, errors)| {
        let e = &errors[0];
        let before = &text[..e.pos.start.min(text.len())];
        let line = before.matches('\n').count() + 1;
        let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
        I18nError {
            file: file.to_path_buf(),
            line,
            column,
            message: e.kind.to_string(),
        }
    })
}

/// An argument of a message.
pub enum Arg<'a> {
    /// A text.
    Str(&'a str),
    /// A number (Fluent picks the plural form from it).
    Num(f64),
}

impl<'a> From<&'a str> for Arg<'a> {
    fn from(s: &'a str) -> Self {
        Arg::Str(s)
    }
}

impl<'a> From<&'a String> for Arg<'a> {
    fn from(s: &'a String) -> Self {
        Arg::Str(s)
    }
}

macro_rules! num_arg {
    ($($t:ty),*) => {$(
        impl From<$t> for Arg<'_> {
            #[allow(clippy::cast_precision_loss, clippy::cast_lossless)]
            fn from(n: $t) -> Self {
                Arg::Num(n as f64)
            }
        }
    )*};
}
num_arg!(u8, u16, u32, u64, usize, i32, i64, f32, f64);

/// The texts of both languages and the one shown.
pub struct I18n {
    lang: Lang,
    bundles: Vec<(Lang, FluentBundle<FluentResource>)>,
}

impl std::fmt::Debug for I18n {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("I18n").field("lang", &self.lang).finish()
    }
}

impl I18n {
    /// The built-in texts, then the plant's (`plant_dir/i18n/<lang>.ftl` when it
    /// exists; a message of the plant overrides a built-in one of the same id).
    pub fn new(lang: Lang, plant_dir: Option<&Path>) -> Result<Self, I18nError> {
        let mut bundles = Vec::new();
        for l in Lang::ALL {
            let mut bundle = FluentBundle::new_concurrent(vec![l.langid()]);
            // egui draws no bidi isolation marks: no FSI/PDI around arguments.
            bundle.set_use_isolating(false);
            let builtin = PathBuf::from(format!("assets/i18n/{}.ftl", l.code()));
            bundle.add_resource_overriding(parse(l.source(), &builtin)?);
            if l == Lang::Fr {
                let file = PathBuf::from("assets/i18n/fr-explain.ftl");
                bundle.add_resource_overriding(parse(FR_EXPLAIN, &file)?);
            }
            if let Some(dir) = plant_dir {
                let file = dir.join("i18n").join(format!("{}.ftl", l.code()));
                if file.exists() {
                    let text = std::fs::read_to_string(&file).map_err(|e| I18nError {
                        file: file.clone(),
                        line: 0,
                        column: 0,
                        message: e.to_string(),
                    })?;
                    bundle.add_resource_overriding(parse(&text, &file)?);
                }
            }
            bundles.push((l, bundle));
        }
        Ok(Self { lang, bundles })
    }

    /// The language shown.
    pub fn lang(&self) -> Lang {
        self.lang
    }

    /// Shows `lang` from the next frame on.
    pub fn set_lang(&mut self, lang: Lang) {
        self.lang = lang;
    }

    fn bundle(&self, lang: Lang) -> Option<&FluentBundle<FluentResource>> {
        self.bundles
            .iter()
            .find(|(l, _)| *l == lang)
            .map(|(_, b)| b)
    }

    fn format(&self, lang: Lang, id: &str, args: Option<&FluentArgs<'_>>) -> Option<String> {
        let bundle = self.bundle(lang)?;
        let pattern = bundle.get_message(id)?.value()?;
        let mut errors = Vec::new();
        let text = bundle.format_pattern(pattern, args, &mut errors);
        Some(text.into_owned())
    }

    /// True when `id` exists in the language shown itself (no fallback).
    pub fn has_own(&self, id: &str) -> bool {
        self.bundle(self.lang).is_some_and(|b| b.has_message(id))
    }

    /// True when `id` exists in the language shown or in English.
    pub fn has(&self, id: &str) -> bool {
        [self.lang, Lang::En]
            .iter()
            .any(|l| self.bundle(*l).is_some_and(|b| b.has_message(id)))
    }

    /// The text of `id`.
    pub fn t(&self, id: &str) -> String {
        self.format(self.lang, id, None)
            .or_else(|| self.format(Lang::En, id, None))
            .unwrap_or_else(|| id.to_string())
    }

    /// The text of `id` with its arguments in English (a record's text, whatever the
    /// language shown).
    pub fn ta_en(&self, id: &str, args: &[(&str, Arg<'_>)]) -> String {
        let mut fa = FluentArgs::new();
        for (k, v) in args {
            match v {
                Arg::Str(s) => fa.set(*k, FluentValue::from(*s)),
                Arg::Num(n) => fa.set(*k, FluentValue::from(*n)),
            }
        }
        self.format(Lang::En, id, Some(&fa))
            .unwrap_or_else(|| id.to_string())
    }

    /// The text of `id` with its arguments.
    pub fn ta(&self, id: &str, args: &[(&str, Arg<'_>)]) -> String {
        let mut fa = FluentArgs::new();
        for (k, v) in args {
            match v {
                Arg::Str(s) => fa.set(*k, FluentValue::from(*s)),
                Arg::Num(n) => fa.set(*k, FluentValue::from(*n)),
            }
        }
        self.format(self.lang, id, Some(&fa))
            .or_else(|| self.format(Lang::En, id, Some(&fa)))
            .unwrap_or_else(|| id.to_string())
    }

    /// An explanation item in the language shown: in English the core's text; in
    /// another language the message of its code (`explain-X201`) built from its fields
    /// (lists spaced, an output's `meaning` from the plant's `off-<output>` when the
    /// plant folder translates it), else the core's text.
    pub fn explain(&self, item: &vigie_core::explain::Item) -> String {
        let id = format!("explain-{}", item.code);
        if self.lang == Lang::En || !self.bundle(self.lang).is_some_and(|b| b.has_message(&id)) {
            return item.text.clone();
        }
        let mut owned: Vec<(String, String)> = Vec::new();
        let mut numbers: Vec<(String, f64)> = Vec::new();
        for (k, v) in &item.fields {
            if NUMBER_FIELDS.contains(&k.as_str()) {
                numbers.push((k.clone(), v.parse().unwrap_or(0.0)));
                continue;
            }
            let mut v = if LIST_FIELDS.contains(&k.as_str()) {
                v.split(',').map(str::trim).collect::<Vec<_>>().join(", ")
            } else {
                v.clone()
            };
            if k == "expected" {
                v = v.replace(" or ", &format!(" {} ", self.t("word-or")));
            }
            if k == "follows" {
                v = v
                    .split(',')
                    .map(|id| {
                        let id = id.trim();
                        self.plant(&format!("observer-{id}"))
                            .map_or_else(|| id.to_string(), |d| format!("{id} = {d}"))
                    })
                    .collect::<Vec<_>>()
                    .join(" ; ");
            }
            if k == "notation" || k == "term" {
                v = vigie_core::explain::overbar_notation(&v);
            }
            if k == "meaning"
                && let Some(m) = item
                    .fields
                    .get("output")
                    .and_then(|o| self.plant(&format!("off-{o}")))
            {
                v = m;
            }
            if k == "place"
                && let Some(p) = self.place(&item.fields)
            {
                v = p;
            }
            if v.is_empty() {
                v = "none".into();
            }
            owned.push((k.clone(), v));
        }
        for key in ["reasons", "observer", "meaning"] {
            if !item.fields.contains_key(key) {
                owned.push((key.into(), "none".into()));
            }
        }
        #[allow(clippy::cast_precision_loss)]
        let n = item
            .fields
            .get("constraints")
            .map_or(1, |c| c.split(',').count()) as f64;
        numbers.push(("n_constraints".into(), n));
        let mut args: Vec<(&str, Arg<'_>)> = owned
            .iter()
            .map(|(k, v)| (k.as_str(), Arg::Str(v.as_str())))
            .collect();
        args.extend(numbers.iter().map(|(k, v)| (k.as_str(), Arg::Num(*v))));
        self.ta(&id, &args)
    }

    /// Where an item was damaged, in the language shown, from the place fields of a
    /// hazard (`place_kind`, `part`, `other`, `other_item`) and the plant's names of its
    /// parts (`part-<id>`); `None` when the fields have no place or the plant folder
    /// does not name a part in this language.
    pub fn place(&self, fields: &std::collections::BTreeMap<String, String>) -> Option<String> {
        let kind = fields.get("place_kind")?;
        // A declared danger of a plant of components is told by its own text.
        if kind == "danger" {
            return self.plant(&format!("danger-{}", fields.get("danger")?));
        }
        let name = |key: &str| self.plant(&format!("part-{}", fields.get(key)?));
        let mut args: Vec<(&str, Arg<'_>)> = Vec::new();
        let part = name("part")?;
        args.push(("part", Arg::Str(&part)));
        let other = if fields.contains_key("other") {
            Some(name("other")?)
        } else {
            None
        };
        if let Some(o) = &other {
            args.push(("other", Arg::Str(o)));
        }
        if let Some(i) = fields.get("other_item") {
            args.push(("other_item", Arg::Str(i)));
        }
        let id = format!("place-{kind}");
        self.has(&id).then(|| self.ta(&id, &args))
    }

    /// A text of the plant's (`signal-C4`…) in the language shown, if it has one.
    pub fn plant(&self, id: &str) -> Option<String> {
        self.format(self.lang, id, None)
    }
}

impl I18n {
    /// The descriptions of `plant`'s signals the plant folder translates into the
    /// language shown (`signal-<id>`), by signal id.
    pub fn signal_descriptions(
        &self,
        plant: &vigie_core::plant::Plant,
    ) -> std::collections::BTreeMap<String, String> {
        plant
            .inputs
            .iter()
            .chain(&plant.outputs)
            .filter_map(|s| Some((s.id.clone(), self.plant(&format!("signal-{}", s.id))?)))
            .collect()
    }
}

/// The message ids of a Fluent file.
pub fn ids(text: &str) -> Vec<String> {
    let res = match FluentResource::try_new(text.to_string()) {
        Ok(r) | Err((r, _)) => r,
    };
    res.entries()
        .filter_map(|e| match e {
            fluent_syntax::ast::Entry::Message(m) => Some(m.id.name.to_string()),
            _ => None,
        })
        .collect()
}

/// The built-in file of `lang`.
pub fn builtin(lang: Lang) -> &'static str {
    lang.source()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_languages_hold_the_same_messages() {
        let en: std::collections::BTreeSet<String> = ids(builtin(Lang::En)).into_iter().collect();
        let fr: std::collections::BTreeSet<String> = ids(builtin(Lang::Fr)).into_iter().collect();
        let only_en: Vec<_> = en.difference(&fr).collect();
        let only_fr: Vec<_> = fr.difference(&en).collect();
        assert!(
            only_en.is_empty() && only_fr.is_empty(),
            "only in en.ftl: {only_en:?}\nonly in fr.ftl: {only_fr:?}"
        );
        // Both parse without error.
        I18n::new(Lang::Fr, None).unwrap();
    }

    /// No file declares a message twice (Fluent keeps one silently: an edit of the other
    /// would change nothing on screen).
    #[test]
    fn no_message_is_declared_twice() {
        let plant = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station/i18n/fr.ftl"),
        )
        .unwrap();
        for (name, text) in [
            ("en.ftl", builtin(Lang::En)),
            ("fr.ftl", builtin(Lang::Fr)),
            ("the station's fr.ftl", plant.as_str()),
        ] {
            let mut seen = std::collections::BTreeSet::new();
            let twice: Vec<String> = ids(text)
                .into_iter()
                .filter(|i| !seen.insert(i.clone()))
                .collect();
            assert!(twice.is_empty(), "{name} declares twice: {twice:?}");
        }
    }

    /// Every `t("…")` / `ta("…"` id in the console's sources is a message.
    #[test]
    fn every_id_used_exists() {
        let i = I18n::new(Lang::En, None).unwrap();
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/console");
        let mut missing = Vec::new();
        let mut used = 0;
        // The console's modules and their own submodules (`synoptic/scene.rs`).
        let mut files = Vec::new();
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                files.extend(std::fs::read_dir(&path).unwrap().map(|e| e.unwrap().path()));
            } else {
                files.push(path);
            }
        }
        for path in files {
            let text = std::fs::read_to_string(&path).unwrap();
            for pat in [".t(", ".ta("] {
                for (pos, _) in text.match_indices(pat) {
                    // The id may be on the next line (a call rustfmt split).
                    let rest = text[pos + pat.len()..].trim_start();
                    let Some(rest) = rest.strip_prefix('"') else {
                        continue;
                    };
                    let id = &rest[..rest.find('"').unwrap()];
                    used += 1;
                    if !i.has(id) {
                        missing.push(format!("{}: {id}", path.display()));
                    }
                }
            }
        }
        assert!(used > 20, "the console uses its messages ({used})");
        assert!(
            missing.is_empty(),
            "missing messages:\n{}",
            missing.join("\n")
        );
    }

    /// The ids the console builds at run time: the synoptic's tags, the states' hover
    /// texts.
    #[test]
    fn built_ids_exist() {
        let i = I18n::new(Lang::Fr, None).unwrap();
        for (k, _) in crate::console::synoptic::TAGS {
            assert!(i.has(&format!("syn-{k}")), "syn-{k}");
        }
        for s in [
            "tripped", "stopped", "manual", "degraded", "idle", "running",
        ] {
            assert!(i.has(&format!("state-{s}-hover")), "state-{s}-hover");
        }
    }

    #[test]
    fn locale_names_and_fallbacks() {
        assert_eq!(Lang::parse("fr_FR.UTF-8"), Some(Lang::Fr));
        assert_eq!(Lang::parse("fr-CA"), Some(Lang::Fr));
        assert_eq!(Lang::parse("en_GB.UTF-8"), Some(Lang::En));
        assert_eq!(Lang::parse("C.UTF-8"), None);
        assert_eq!(Lang::parse("de_DE"), None);
        let mut i = I18n::new(Lang::Fr, None).unwrap();
        assert_eq!(i.t("no-such-message"), "no-such-message");
        let fr = i.t("state-running");
        i.set_lang(Lang::En);
        assert_ne!(fr, i.t("state-running"));
    }

    #[test]
    fn a_broken_plant_file_names_its_line_and_column() {
        let dir = std::env::temp_dir().join(format!("vigie-i18n-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("i18n")).unwrap();
        std::fs::write(dir.join("i18n/fr.ftl"), "signal-C4 = Table\n\n= oops\n").unwrap();
        let e = I18n::new(Lang::Fr, Some(&dir)).unwrap_err().to_string();
        assert!(e.contains("i18n/fr.ftl:3:1"), "{e}");
        std::fs::write(dir.join("i18n/fr.ftl"), "signal-C4 = Table en chargement\n").unwrap();
        let i = I18n::new(Lang::Fr, Some(&dir)).unwrap();
        assert_eq!(i.plant("signal-C4").as_deref(), Some("Table en chargement"));
        assert_eq!(i.plant("signal-C5"), None);
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[cfg(test)]
mod explain_tests {
    use super::*;

    /// An explanation item with its fields, as the core records it.
    fn item(code: &'static str, text: &str, fields: &[(&str, &str)]) -> vigie_core::explain::Item {
        vigie_core::explain::Item {
            code,
            text: text.into(),
            fields: fields
                .iter()
                .map(|(k, v)| ((*k).into(), (*v).into()))
                .collect(),
        }
    }

    /// Every code of `core/src/explain/codes.md` has its French message.
    #[test]
    fn every_explanation_code_has_a_french_message() {
        let codes = include_str!("../../core/src/explain/codes.md");
        let fr: std::collections::BTreeSet<String> = ids(FR_EXPLAIN).into_iter().collect();
        let mut missing = Vec::new();
        let mut n = 0;
        for line in codes.lines() {
            if let Some(code) = line.strip_prefix("| X").and_then(|r| r.split(' ').next()) {
                n += 1;
                if !fr.contains(&format!("explain-X{code}")) {
                    missing.push(format!("X{code}"));
                }
            }
        }
        assert!(n > 20, "codes read: {n}");
        assert!(missing.is_empty(), "no French message for {missing:?}");
    }

    /// Every alarm code the core writes has its French message.
    #[test]
    fn every_alarm_code_has_a_french_message() {
        let fr: std::collections::BTreeSet<String> = ids(FR_EXPLAIN).into_iter().collect();
        let core = [
            include_str!("../../core/src/sim/diagnosis.rs"),
            include_str!("../../core/src/plausibility.rs"),
        ];
        let mut codes = Vec::new();
        for text in core {
            for (pos, _) in text
                .match_indices("\"diagnosis-")
                .chain(text.match_indices("\"plausibility-"))
            {
                let rest = &text[pos + 1..];
                codes.push(rest[..rest.find('"').unwrap()].to_string());
            }
        }
        codes.extend(["hazard".to_string(), "task".to_string()]);
        assert!(codes.len() >= 10, "{codes:?}");
        let missing: Vec<_> = codes
            .iter()
            .filter(|c| !fr.contains(&format!("alarm-{c}")))
            .collect();
        assert!(missing.is_empty(), "no French message for {missing:?}");
    }

    #[test]
    fn an_item_in_french_from_its_fields() {
        let mut i = I18n::new(Lang::Fr, None).unwrap();
        let x301 = item(
            "X301",
            "C7 changed 0→1 at 11680 ms (in the stopping cycle), element of the constraint.",
            &[
                ("signal", "C7"),
                ("from", "0"),
                ("to", "1"),
                ("time_ms", "11680"),
                ("ms_before", "0"),
                ("in_constraint", "true"),
            ],
        );
        assert_eq!(
            i.explain(&x301),
            "C7 est passé de 0 à 1 à 11680 ms (dans le cycle de l'arrêt), élément de la contrainte."
        );
        let x001 = item(
            "X001",
            "…",
            &[("time_ms", "11680"), ("constraints", "CSs10,CSs14")],
        );
        assert_eq!(
            i.explain(&x001),
            "Le filtre de sécurité a arrêté la machine à 11680 ms : CSs10, CSs14 auraient été violées."
        );
        let x403 = item("X403", "…", &[("expected", "A2=0 or A3=0")]);
        assert_eq!(i.explain(&x403), "Attendu de la commande : A2=0 ou A3=0.");
        let x201 = item(
            "X201",
            "…",
            &[
                ("constraint", "CSs10"),
                ("notation", "C7 . /A4"),
                ("values", "C7=1,A4=0"),
            ],
        );
        assert!(i.explain(&x201).contains('\u{305}'), "{}", i.explain(&x201));
        // A sum of terms: the term that became true, not the whole sum.
        let x201 = item(
            "X201",
            "…",
            &[
                ("constraint", "DSTOP_P"),
                ("notation", "/C5 . A4 . def_P + A0 . def_P"),
                ("term", "A0 . def_P"),
                ("multi", "yes"),
                ("values", "A0=1,def_P=1"),
            ],
        );
        assert_eq!(
            i.explain(&x201),
            "DSTOP_P : son terme A0 · def_P est devenu vrai : A0=1, def_P=1."
        );
        // X417: the action in the wrong step, from the step's exits.
        let x417 = item(
            "X417",
            "…",
            &[
                ("output", "A3"),
                ("chart", "table"),
                ("step", "X23"),
                ("qualifier", "N"),
                ("constraint", "CSs5"),
                ("condition", "/C5"),
                ("evidence", "exits"),
                ("activated_by", "t22"),
                ("receptivity", "C5"),
                ("exits", "t23"),
                ("ms_before", "0"),
            ],
        );
        assert_eq!(
            i.explain(&x417),
            "L'action N A3 de l'étape X23 commande A3 dans la situation où CSs5 l'interdit (/C5) : les transitions qui la quittent, t23 (`C5`), attendent la fin de cette situation. L'action de X23 sur A3 est suspecte : elle appartient à une autre étape."
        );
        // In English, the core's text, untouched.
        i.set_lang(Lang::En);
        assert_eq!(i.explain(&x301), x301.text);
        // A code without a French message keeps the core's text.
        i.set_lang(Lang::Fr);
        let unknown = item("X999", "as the core wrote it", &[]);
        assert_eq!(i.explain(&unknown), "as the core wrote it");
    }

    /// X418 in French: the observer the expectation follows, in the plant's words.
    #[test]
    fn an_unexpected_edge_in_french() {
        let i = I18n::new(Lang::Fr, None).unwrap();
        // X418: the observer the expectation follows, in the plant's French words.
        let x418 = item(
            "X418",
            "…",
            &[
                ("sensor", "C6"),
                ("from", "0"),
                ("to", "1"),
                ("expected", "P36*"),
                ("follows", "P36"),
            ],
        );
        assert!(
            i.explain(&x418).starts_with(
                "C6 est passé de 0 à 1 au cycle d'arrêt alors que la physique de la machine ne l'attendait pas (seulement quand P36* : P36)"
            ),
            "{}",
            i.explain(&x418)
        );
        // With the plant folder, the observer in the plant's French words.
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
        let with_plant = I18n::new(Lang::Fr, Some(&dir)).unwrap();
        assert!(
            with_plant
                .explain(&x418)
                .contains("(seulement quand P36* : P36 = une caisse entre C3 et C6 (exclus)"),
            "{}",
            with_plant.explain(&x418)
        );
    }
}

#[cfg(test)]
mod plant_tests {
    use super::*;

    /// Every scenario file, every variant of the control-error library, every
    /// plant-fault exercise and every task of the station has its French text, and the plant folder holds no text for a file or a variant
    /// that does not exist (a renamed scenario would lose its title silently).
    #[test]
    fn the_station_titles_its_scenarios_and_variants_in_french() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
        let fr = I18n::new(Lang::Fr, Some(&dir)).unwrap();
        let mut expected = std::collections::BTreeSet::new();
        for e in std::fs::read_dir(dir.join("scenarios")).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "ron") {
                expected.insert(format!(
                    "scenario-{}",
                    p.file_stem().unwrap().to_string_lossy()
                ));
            }
        }
        let (bundle, _) = vigie_core::bundle::PlantBundle::load(&dir).unwrap();
        let lib = vigie_core::control::ErrorLibrary::load(
            &dir.join("programs/errors.ron"),
            &bundle.plant,
        )
        .unwrap();
        for v in &lib.variants {
            expected.insert(format!("variant-{}", v.def.id));
        }
        let exercises =
            vigie_core::emulator::load_exercises(&dir.join("exercises.ron"), &bundle.plant, None)
                .unwrap();
        for e in &exercises {
            expected.insert(format!("exercise-{}", e.id));
        }
        for t in bundle.tasks.iter().flat_map(|t| t.tasks.iter()) {
            expected.insert(format!("task-{}", t.id));
        }
        for o in &bundle.observers.defs {
            expected.insert(format!("observer-{}", o.id));
        }
        for id in &expected {
            assert!(fr.plant(id).is_some(), "{id} has no French text");
        }
        let text = std::fs::read_to_string(dir.join("i18n/fr.ftl")).unwrap();
        for id in ids(&text) {
            if ["scenario-", "variant-", "exercise-", "task-", "observer-"]
                .iter()
                .any(|p| id.starts_with(p))
            {
                assert!(expected.contains(&id), "{id} names nothing");
            }
        }
    }

    /// Every part of the station's layout has a French name, and a damaged item's place
    /// is told with it (not with layout.ron's English name).
    #[test]
    fn a_damaged_items_place_in_french() {
        use vigie_core::emulator::Place;
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
        let layout = vigie_core::machine::Description::load(&dir)
            .unwrap()
            .layout()
            .unwrap();
        let fr = I18n::new(Lang::Fr, Some(&dir)).unwrap();
        for id in layout
            .conveyors
            .iter()
            .map(|c| &c.id)
            .chain([&layout.table.id])
        {
            assert!(fr.plant(&format!("part-{id}")).is_some(), "part-{id}");
        }
        let sheared = vigie_core::explain::Item {
            code: "X101",
            text: "Without the filter, 76 ms later: box 1 would be sheared at the edge of the Roller turntable (A4, A2, A3).".into(),
            fields: [
                ("kind", "Sheared"),
                ("place", "edge of the Roller turntable"),
                ("box", "1"),
                ("after_ms", "76"),
                ("elements", "A4,A2,A3"),
            ]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .chain(Place::Edge { part: layout.table.id.clone() }.fields())
            .collect(),
        };
        let t = fr.explain(&sheared);
        assert!(t.contains("Table tournante (bord)"), "{t}");
        assert!(!t.contains("Roller"), "{t}");
        let between: std::collections::BTreeMap<String, String> = Place::Between {
            part: "intermediate".into(),
            other: "table".into(),
        }
        .fields()
        .into_iter()
        .collect();
        assert_eq!(
            fr.place(&between).as_deref(),
            Some("jonction Convoyeur intermédiaire / Table tournante")
        );
        // A part the plant folder does not name: no place of our own (the core's text
        // stays).
        let unknown: std::collections::BTreeMap<String, String> = Place::Edge {
            part: "nowhere".into(),
        }
        .fields()
        .into_iter()
        .collect();
        assert_eq!(fr.place(&unknown), None);
    }

    /// The sorting station's folder translates every signal it describes.
    #[test]
    fn the_station_describes_every_signal_in_french() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
        let (bundle, _) = vigie_core::bundle::PlantBundle::load(&dir).unwrap();
        let i = I18n::new(Lang::Fr, Some(&dir)).unwrap();
        let d = i.signal_descriptions(&bundle.plant);
        assert_eq!(
            d.len(),
            bundle.plant.inputs.len() + bundle.plant.outputs.len()
        );
        assert!(d["C4"].contains("position de chargement"), "{}", d["C4"]);
        let en = I18n::new(Lang::En, Some(&dir)).unwrap();
        assert!(
            en.signal_descriptions(&bundle.plant).is_empty(),
            "English: plant.ron's own"
        );
    }
}
