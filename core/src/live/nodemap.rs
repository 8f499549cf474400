//! The OPC UA node map: which node of an OPC UA server holds every plant signal, how
//! often it is read and how old it may get before it is stale. The OPC UA counterpart
//! of the Modbus [`super::iomap`]; the link's cycle sees neither, only the staleness
//! bounds.
//!
//! Written in RON next to the plant (`node-map.ron`); a node is an OPC UA node id in
//! its standard text form (`ns=4;s=GVL.C0`, `nsu=urn:plc;i=1001`; without `ns=` or
//! `nsu=`, in the map's `namespace`) or a browse path from the Objects folder, each
//! element in the map's namespace unless it says `N:` (`Plant/Inputs/C0`,
//! `0:Server/0:ServerStatus`):
//!
//! ```ron
//! NodeMap(
//!     namespace: "urn:vigie:sorting-station",
//!     poll_ms: 10,
//!     signals: [
//!         (signal: "C0", node: "s=C0"),
//!         (signal: "A0", path: "Plant/Outputs/A0", poll_ms: 20),
//!     ],
//! )
//! ```
//!
//! Without a file, [`NodeMap::from_plant`] puts every signal at `s=<signal id>` in the
//! namespace `urn:vigie:<plant folder>`: the address space Vigie's own server publishes.
//! Whether the server has the nodes, and whether they are Booleans, is checked by the
//! client at every connection (the server is not known at load).

use super::ron_options;
use crate::diag::codes;
use crate::diag::{Location, Problem, ron_problem};
use crate::plant::Plant;
use crate::time::Millis;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The namespace of a node id or of a browse name.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Namespace {
    /// A namespace index of the server (`ns=2`): only valid on that server.
    Index(u16),
    /// A namespace URI (`nsu=urn:…`), looked up in the server's namespace array.
    Uri(String),
}

/// The identifier part of a node id.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Identifier {
    /// `i=1001`.
    Numeric(u32),
    /// `s=GVL.C0`.
    String(String),
    /// `g=72962B91-FA75-4AE6-8D28-B404DC7DAF63` (kept as written, upper case).
    Guid(String),
    /// `b=M/RbKBsRVkePCePcx24oRA==` (base64, kept as written).
    Opaque(String),
}

/// Where a signal is on the server.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum NodeRef {
    /// A node id.
    Id {
        /// Its namespace.
        namespace: Namespace,
        /// Its identifier.
        identifier: Identifier,
    },
    /// A browse path from the Objects folder: one browse name per element.
    Path(Vec<(Namespace, String)>),
}

impl std::fmt::Display for Namespace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Index(i) => write!(f, "ns={i}"),
            Self::Uri(u) => write!(f, "nsu={u}"),
        }
    }
}

impl std::fmt::Display for NodeRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Id {
                namespace,
                identifier,
            } => {
                write!(f, "{namespace};")?;
                match identifier {
                    Identifier::Numeric(n) => write!(f, "i={n}"),
                    Identifier::String(s) => write!(f, "s={s}"),
                    Identifier::Guid(g) => write!(f, "g={g}"),
                    Identifier::Opaque(b) => write!(f, "b={b}"),
                }
            }
            Self::Path(elements) => {
                for (k, (ns, name)) in elements.iter().enumerate() {
                    if k > 0 {
                        f.write_str("/")?;
                    }
                    match ns {
                        Namespace::Index(i) => write!(f, "{i}:{name}")?,
                        Namespace::Uri(u) => write!(f, "<{u}>{name}")?,
                    }
                }
                Ok(())
            }
        }
    }
}

/// Parses a node id in the OPC UA text form; `default` is the namespace of an id
/// written without `ns=` or `nsu=`. The error says what is wrong, in words.
pub fn parse_node_id(text: &str, default: &str) -> Result<NodeRef, String> {
    let text = text.trim();
    let (namespace, rest) = if let Some(r) = text.strip_prefix("nsu=") {
        let (uri, rest) = r.split_once(';').ok_or_else(|| {
            format!("`{text}`: `nsu=URI` must be followed by `;` and the identifier")
        })?;
        if uri.is_empty() {
            return Err(format!("`{text}`: the namespace URI is empty"));
        }
        (Namespace::Uri(uri.to_string()), rest)
    } else if let Some(r) = text.strip_prefix("ns=") {
        let (index, rest) = r.split_once(';').ok_or_else(|| {
            format!("`{text}`: `ns=N` must be followed by `;` and the identifier")
        })?;
        let index = index.parse::<u16>().map_err(|_| {
            format!("`{text}`: the namespace index `{index}` is not a number from 0 to 65535")
        })?;
        (Namespace::Index(index), rest)
    } else {
        (Namespace::Uri(default.to_string()), text)
    };
    let identifier = match rest.split_at_checked(2) {
        Some(("i=", n)) => Identifier::Numeric(n.parse().map_err(|_| {
            format!("`{text}`: `i=` takes a number from 0 to 4294967295, not `{n}`")
        })?),
        Some(("s=", s)) if !s.is_empty() => Identifier::String(s.to_string()),
        Some(("g=", g)) if is_guid(g) => Identifier::Guid(g.to_ascii_uppercase()),
        Some(("g=", g)) => {
            return Err(format!(
                "`{text}`: `{g}` is not a GUID (8-4-4-4-12 hexadecimal digits)"
            ));
        }
        Some(("b=", b)) if is_base64(b) => Identifier::Opaque(b.to_string()),
        Some(("b=", b)) => return Err(format!("`{text}`: `{b}` is not base64")),
        _ => {
            return Err(format!(
                "`{text}` is not a node id: write `s=NAME`, `i=NUMBER`, `g=GUID` or `b=BASE64`, optionally after `ns=INDEX;` or `nsu=URI;`"
            ));
        }
    };
    Ok(NodeRef::Id {
        namespace,
        identifier,
    })
}

/// Parses a browse path from the Objects folder (`Plant/Inputs/C0`, `2:Plant/2:C0`);
/// an element without `N:` is in `default`.
pub fn parse_path(text: &str, default: &str) -> Result<NodeRef, String> {
    let mut elements = Vec::new();
    for element in text.trim().trim_start_matches('/').split('/') {
        let (namespace, name) = match element.split_once(':') {
            Some((index, name))
                if !index.is_empty() && index.bytes().all(|b| b.is_ascii_digit()) =>
            {
                (
                    Namespace::Index(index.parse().map_err(|_| {
                        format!("`{text}`: the namespace index `{index}` is past 65535")
                    })?),
                    name,
                )
            }
            _ => (Namespace::Uri(default.to_string()), element),
        };
        if name.trim().is_empty() {
            return Err(format!(
                "`{text}`: a browse path has no empty element (write `Folder/Name`)"
            ));
        }
        elements.push((namespace, name.to_string()));
    }
    Ok(NodeRef::Path(elements))
}

fn is_guid(g: &str) -> bool {
    let parts: Vec<&str> = g.split('-').collect();
    parts.len() == 5
        && parts
            .iter()
            .zip([8, 4, 4, 4, 12])
            .all(|(p, n)| p.len() == n && p.bytes().all(|b| b.is_ascii_hexdigit()))
}

fn is_base64(b: &str) -> bool {
    !b.is_empty()
        && b.len().is_multiple_of(4)
        && b.bytes()
            .all(|c| c.is_ascii_alphanumeric() || c == b'+' || c == b'/' || c == b'=')
}

/// One line of the map as written: a signal and either `node` or `path`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeEntry {
    /// Plant signal id.
    pub signal: String,
    /// A node id in the OPC UA text form.
    #[serde(default)]
    pub node: Option<String>,
    /// A browse path from the Objects folder.
    #[serde(default)]
    pub path: Option<String>,
    /// Read period in ms, when not the map's.
    #[serde(default)]
    pub poll_ms: Option<u64>,
    /// Staleness bound in ms, when not the map's.
    #[serde(default)]
    pub max_age_ms: Option<u64>,
}

fn default_poll_ms() -> u64 {
    10
}

/// The map file as written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "NodeMap")]
pub struct NodeMapFile {
    /// The namespace URI of nodes and browse names written without one.
    pub namespace: String,
    /// Default read period in ms (10).
    #[serde(default = "default_poll_ms")]
    pub poll_ms: u64,
    /// Default staleness bound in ms (three read periods when absent).
    #[serde(default)]
    pub max_age_ms: Option<u64>,
    /// One entry per plant signal.
    pub signals: Vec<NodeEntry>,
}

/// A signal placed on the server.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MappedNode {
    /// The plant signal.
    pub signal: String,
    /// Where it is.
    pub node: NodeRef,
    /// How often it is read.
    pub poll: Millis,
    /// How old its value may get before it is stale.
    pub max_age: Millis,
    /// Where it was written (file, line, column), for the problems found at connection.
    pub at: Option<Location>,
}

impl super::Placed for MappedNode {
    fn poll(&self) -> Millis {
        self.poll
    }
    fn max_age(&self) -> Millis {
        self.max_age
    }
}

/// A validated node map: one [`MappedNode`] per plant input and output, in plant order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NodeMap {
    /// The map's namespace URI.
    pub namespace: String,
    /// Sensors, indexed like `Plant::inputs`.
    pub inputs: Vec<MappedNode>,
    /// Actuators, indexed like `Plant::outputs`.
    pub outputs: Vec<MappedNode>,
}

/// The namespace URI of the address space Vigie serves for the plant in `folder`.
pub fn plant_namespace(folder: &Path) -> String {
    let name = folder
        .canonicalize()
        .ok()
        .and_then(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "plant".to_string());
    format!("urn:vigie:{name}")
}

impl NodeMap {
    /// Loads and validates a map file against `plant`: the map and its warnings, or
    /// every error found.
    pub fn load(path: &Path, plant: &Plant) -> Result<(Self, Vec<Problem>), Vec<Problem>> {
        let text = crate::diag::read_text(path).map_err(|p| {
            vec![Problem::error(
                codes::IO_MAP_UNREADABLE.id,
                p.message,
                p.location,
            )]
        })?;
        Self::from_ron(&text, path, plant)
    }

    /// Parses and validates map text; `file` is used in messages only.
    pub fn from_ron(
        text: &str,
        file: &Path,
        plant: &Plant,
    ) -> Result<(Self, Vec<Problem>), Vec<Problem>> {
        let parsed: NodeMapFile = ron_options()
            .from_str(text)
            .map_err(|e| vec![ron_problem(file, &e)])?;
        Self::from_file(&parsed, plant, text, file)
    }

    /// The map of the address space Vigie serves: every signal at `s=<id>` in
    /// `namespace`, read every `poll_ms`.
    pub fn from_plant(plant: &Plant, namespace: &str, poll_ms: u64) -> Self {
        let mapped = |id: &str| MappedNode {
            signal: id.to_string(),
            node: NodeRef::Id {
                namespace: Namespace::Uri(namespace.to_string()),
                identifier: Identifier::String(id.to_string()),
            },
            poll: Millis(poll_ms.max(1)),
            max_age: Millis(poll_ms.max(1).saturating_mul(3)),
            at: None,
        };
        Self {
            namespace: namespace.to_string(),
            inputs: plant.inputs.iter().map(|s| mapped(&s.id)).collect(),
            outputs: plant.outputs.iter().map(|s| mapped(&s.id)).collect(),
        }
    }

    /// Validates a parsed map: every signal mapped exactly once, on a node that parses,
    /// no two signals on the same node, non-zero periods.
    pub fn from_file(
        file: &NodeMapFile,
        plant: &Plant,
        text: &str,
        path: &Path,
    ) -> Result<(Self, Vec<Problem>), Vec<Problem>> {
        let mut errors = Vec::new();
        let mut warnings = Vec::new();
        let at = |needle: &str| Some(Location::of_nth(path, text, needle, 0));
        if file.poll_ms == 0 {
            errors.push(Problem::error(
                codes::IO_MAP_POLL.id,
                "poll_ms must be at least 1",
                at("poll_ms"),
            ));
        }
        let mut inputs: Vec<Option<MappedNode>> = vec![None; plant.inputs.len()];
        let mut outputs: Vec<Option<MappedNode>> = vec![None; plant.outputs.len()];
        let mut taken: BTreeMap<NodeRef, String> = BTreeMap::new();
        for e in &file.signals {
            let loc = at(&format!("\"{}\"", e.signal));
            let node = match entry_node(e, &file.namespace) {
                Ok(n) => n,
                Err(why) => {
                    errors.push(Problem::error(
                        codes::OPCUA_NODE_INVALID.id,
                        format!("`{}`: {why}", e.signal),
                        loc,
                    ));
                    continue;
                }
            };
            let poll = e.poll_ms.unwrap_or(file.poll_ms);
            let max_age = e
                .max_age_ms
                .or(file.max_age_ms)
                .unwrap_or_else(|| poll.saturating_mul(3));
            if e.poll_ms == Some(0) {
                errors.push(Problem::error(
                    codes::IO_MAP_POLL.id,
                    format!("`{}`: poll_ms must be at least 1", e.signal),
                    loc.clone(),
                ));
            }
            if max_age < poll {
                warnings.push(Problem::warning(
                    codes::IO_MAP_MAX_AGE.id,
                    format!(
                        "`{}`: max_age_ms {max_age} is below the read period {poll}: the value will be stale between reads",
                        e.signal
                    ),
                    loc.clone(),
                ));
            }
            if let Some(other) = taken.insert(node.clone(), e.signal.clone()) {
                errors.push(Problem::error(
                    codes::OPCUA_NODE_SHARED.id,
                    format!("`{}` and `{other}` are both on node {node}", e.signal),
                    loc.clone(),
                ));
            }
            let slot = if let Some(i) = plant.input(&e.signal) {
                inputs.get_mut(i)
            } else if let Some(k) = plant.output(&e.signal) {
                outputs.get_mut(k)
            } else {
                errors.push(Problem::error(
                    codes::IO_MAP_UNKNOWN_SIGNAL.id,
                    format!("`{}` is not a signal of plant `{}`", e.signal, plant.name),
                    loc,
                ));
                continue;
            };
            if let Some(slot) = slot {
                if slot.is_some() {
                    errors.push(Problem::error(
                        codes::IO_MAP_DUPLICATE.id,
                        format!("`{}` is mapped twice", e.signal),
                        loc.clone(),
                    ));
                }
                *slot = Some(MappedNode {
                    signal: e.signal.clone(),
                    node,
                    poll: Millis(poll.max(1)),
                    max_age: Millis(max_age),
                    at: loc,
                });
            }
        }
        errors.extend(super::unmapped(plant, &inputs, &outputs, path));
        if !errors.is_empty() {
            errors.extend(warnings);
            return Err(errors);
        }
        Ok((
            Self {
                namespace: file.namespace.clone(),
                inputs: inputs.into_iter().flatten().collect(),
                outputs: outputs.into_iter().flatten().collect(),
            },
            warnings,
        ))
    }

    /// The smallest read period of the map.
    pub fn fastest_poll(&self) -> Millis {
        super::fastest_poll(self.inputs.iter().chain(&self.outputs))
    }

    /// Staleness bounds of the inputs, in input order.
    pub fn input_bounds(&self) -> Vec<Millis> {
        super::input_bounds(self.inputs.iter())
    }
}

fn entry_node(e: &NodeEntry, namespace: &str) -> Result<NodeRef, String> {
    match (&e.node, &e.path) {
        (Some(n), None) => parse_node_id(n, namespace),
        (None, Some(p)) => parse_path(p, namespace),
        (Some(_), Some(_)) => Err("give `node` or `path`, not both".to_string()),
        (None, None) => {
            Err("give its `node` (a node id) or its `path` (a browse path)".to_string())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plant() -> Plant {
        Plant::load(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/single-conveyor/plant.ron"),
        )
        .unwrap()
    }

    #[test]
    fn node_ids_parse_in_every_form_and_print_back() {
        for (text, shown) in [
            ("s=C0", "nsu=urn:d;s=C0"),
            (
                "ns=4;s=|var|CODESYS Control.Application.GVL.C0",
                "ns=4;s=|var|CODESYS Control.Application.GVL.C0",
            ),
            ("nsu=urn:plc;i=1001", "nsu=urn:plc;i=1001"),
            ("ns=0;i=2258", "ns=0;i=2258"),
            (
                "g=72962b91-fa75-4ae6-8d28-b404dc7daf63",
                "nsu=urn:d;g=72962B91-FA75-4AE6-8D28-B404DC7DAF63",
            ),
            (
                "b=M/RbKBsRVkePCePcx24oRA==",
                "nsu=urn:d;b=M/RbKBsRVkePCePcx24oRA==",
            ),
        ] {
            let n = parse_node_id(text, "urn:d").unwrap();
            assert_eq!(n.to_string(), shown);
            let again = parse_node_id(&n.to_string(), "urn:other").unwrap();
            assert_eq!(again, n, "{text}");
        }
    }

    #[test]
    fn mistyped_node_ids_say_what_is_wrong() {
        for (text, says) in [
            ("ns=x;s=C0", "namespace index `x`"),
            ("ns=70000;s=C0", "65535"),
            ("ns=2", "followed by `;`"),
            ("nsu=;s=C0", "URI is empty"),
            ("i=-1", "`i=` takes a number"),
            ("g=1234", "not a GUID"),
            ("b=%%", "not base64"),
            ("C0", "not a node id"),
            ("s=", "not a node id"),
        ] {
            let e = parse_node_id(text, "urn:d").unwrap_err();
            assert!(e.contains(says), "{text}: {e}");
        }
    }

    #[test]
    fn browse_paths_take_the_map_namespace_unless_indexed() {
        let p = parse_path("/Plant/2:Inputs/C0", "urn:d").unwrap();
        assert_eq!(p.to_string(), "<urn:d>Plant/2:Inputs/<urn:d>C0");
        assert!(
            parse_path("Plant//C0", "urn:d")
                .unwrap_err()
                .contains("empty element")
        );
    }

    #[test]
    fn a_map_is_checked_against_the_plant_with_file_line_and_column() {
        let plant = plant();
        let mut text = String::from("NodeMap(namespace: \"urn:t\", signals: [\n");
        for s in plant.inputs.iter().chain(&plant.outputs) {
            text.push_str(&format!(
                "    (signal: \"{}\", node: \"s={}\"),\n",
                s.id, s.id
            ));
        }
        text.push_str("])\n");
        let (map, warnings) = NodeMap::from_ron(&text, Path::new("m.ron"), &plant).unwrap();
        assert!(warnings.is_empty());
        assert_eq!(map.inputs.len(), plant.inputs.len());
        assert_eq!(map, {
            let mut m = NodeMap::from_plant(&plant, "urn:t", 10);
            for (a, b) in m
                .inputs
                .iter_mut()
                .chain(m.outputs.iter_mut())
                .zip(map.inputs.iter().chain(&map.outputs))
            {
                a.at.clone_from(&b.at);
            }
            m
        });
        let first = &plant.inputs[0].id;
        let second = &plant.inputs[1].id;
        let bad = text
            .replace(&format!("node: \"s={first}\""), "node: \"ns=x;s=A\"")
            .replace(
                &format!("node: \"s={second}\""),
                &format!("path: \"Plant/{second}\", node: \"s={second}\""),
            )
            .replace("])", "    (signal: \"ZZ9\", node: \"s=ZZ9\"),\n])");
        let errors = NodeMap::from_ron(&bad, Path::new("m.ron"), &plant).unwrap_err();
        let shown = crate::diag::render(&errors);
        assert!(
            shown.contains("m.ron:2:") && shown.contains(codes::OPCUA_NODE_INVALID.id),
            "{shown}"
        );
        assert!(shown.contains("not both"), "{shown}");
        assert!(shown.contains("`ZZ9` is not a signal"), "{shown}");
        assert!(shown.contains("signals not mapped"), "{shown}");
        let shared = text.replace(
            &format!("node: \"s={second}\""),
            &format!("node: \"s={first}\""),
        );
        let errors = NodeMap::from_ron(&shared, Path::new("m.ron"), &plant).unwrap_err();
        assert!(
            errors.iter().any(|p| p.code == codes::OPCUA_NODE_SHARED.id),
            "{errors:?}"
        );
    }
}
