//! The OPC UA sections of the gateway configuration: the client Vigie is to an OPC UA
//! plant or PLC, and the server it is to an OPC UA PLC or client. Pure: the networking
//! (async-opcua) is in the app.
//!
//! ```ron
//! client: OpcUa(
//!     endpoint: "opc.tcp://192.168.0.10:4840/",
//!     security: SignAndEncrypt,                 // Basic256Sha256; or Sign, or None (loopback only)
//!     server_certificate: "pki/plc-server.der", // the peer's certificate, trusted explicitly
//!     user: "vigie", password_file: "secrets/opcua-password",
//!     node_map: "node-map.ron",                 // else the plant's own address space
//! ),
//! server: OpcUa(
//!     bind: "127.0.0.1:4840",
//!     security: [SignAndEncrypt],
//!     users: [(name: "plc", password_hash: "$argon2id$v=19$…")],
//!     plc_user: "plc",                          // the only identity that may write outputs
//!     trusted_clients: ["pki/plc-client.der"],
//! ),
//! ```

use crate::diag::codes;
use crate::diag::{Location, Problem};
use serde::{Deserialize, Serialize};
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::{Path, PathBuf};

/// The message security of an endpoint (policy Basic256Sha256 unless `None`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Security {
    /// No signature, no encryption: loopback only (tests, a simulator on the machine).
    None,
    /// Basic256Sha256, messages signed.
    Sign,
    /// Basic256Sha256, messages signed and encrypted.
    SignAndEncrypt,
}

impl std::fmt::Display for Security {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::None => "None",
            Self::Sign => "Basic256Sha256 Sign",
            Self::SignAndEncrypt => "Basic256Sha256 SignAndEncrypt",
        })
    }
}

/// Which time a value read over OPC UA is aged from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Timestamps {
    /// The time the Read request was sent (the default): a Read with `maxAge = 0`
    /// asks the server for the value now, so the value was current at least then,
    /// as for a Modbus read. Right for every server.
    #[default]
    Request,
    /// The value's SourceTimestamp (else its ServerTimestamp), on Vigie's clock, never
    /// later than the request: the age at the source itself. Only for a server that
    /// stamps every sample (a PLC runtime's own server stamping its I/O image each
    /// task cycle); a server that stamps changes only would age every steady value
    /// until it is stale. Needs the two clocks synchronised (NTP).
    Source,
}

fn default_security() -> Security {
    Security::SignAndEncrypt
}
fn default_securities() -> Vec<Security> {
    vec![Security::SignAndEncrypt]
}
fn default_timeout_ms() -> u64 {
    200
}
fn default_bind() -> SocketAddr {
    SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), 4840)
}

/// The OPC UA client Vigie is to the plant (gateway) or to the monitored PLC (monitor).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OpcUaClientConfig {
    /// The server's endpoint URL, `opc.tcp://HOST:PORT/PATH`.
    pub endpoint: String,
    /// The security asked of the server's endpoint (`SignAndEncrypt` by default).
    #[serde(default = "default_security")]
    pub security: Security,
    /// The server's certificate (DER), trusted explicitly (relative to the
    /// configuration's folder). Without it, a secure connection is refused until the
    /// certificate the server presented, kept in the PKI's `rejected` folder, is moved
    /// to its `trusted` folder.
    #[serde(default)]
    pub server_certificate: Option<PathBuf>,
    /// A user name; anonymous when absent.
    #[serde(default)]
    pub user: Option<String>,
    /// The file holding the user's password (its first line), relative to the
    /// configuration's folder.
    #[serde(default)]
    pub password_file: Option<PathBuf>,
    /// The node map; the plant folder's `node-map.ron` when it has one, else the
    /// address space Vigie serves for the plant (`s=<signal>` in `urn:vigie:<plant>`).
    #[serde(default)]
    pub node_map: Option<PathBuf>,
    /// Which time a value is aged from: `Request` (default) or `Source`.
    #[serde(default)]
    pub timestamps: Timestamps,
    /// Time allowed for one request (and for connecting, ten times this).
    #[serde(default = "default_timeout_ms")]
    pub timeout_ms: u64,
    /// First reconnection delay, doubled after each failure.
    #[serde(default = "super::config::default_backoff_initial_ms")]
    pub backoff_initial_ms: u64,
    /// Largest reconnection delay.
    #[serde(default = "super::config::default_backoff_max_ms")]
    pub backoff_max_ms: u64,
}

/// One user of Vigie's OPC UA server.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OpcUaUser {
    /// The user name.
    pub name: String,
    /// The password's argon2 hash (a PHC string, `$argon2id$…`; `vigie opcua hash-password`).
    pub password_hash: String,
}

/// The OPC UA server Vigie is to a PLC (gateway) or to a soft-PLC (emulator).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OpcUaServerConfig {
    /// Address to listen on; `127.0.0.1:4840` by default. Port 0 lets the OS choose.
    #[serde(default = "default_bind")]
    pub bind: SocketAddr,
    /// The endpoints offered (`[SignAndEncrypt]` by default).
    #[serde(default = "default_securities")]
    pub security: Vec<Security>,
    /// The users who may open a session.
    #[serde(default)]
    pub users: Vec<OpcUaUser>,
    /// Anonymous sessions allowed (read-only unless `plc_user` is `"anonymous"`);
    /// false by default.
    #[serde(default)]
    pub anonymous: bool,
    /// The only identity that may write the outputs (the PLC's user, or `"anonymous"`);
    /// without it the server is read-only. Inputs are never writable.
    #[serde(default)]
    pub plc_user: Option<String>,
    /// Client certificates (DER) trusted explicitly, relative to the configuration's
    /// folder; any other certificate is refused and kept in the PKI's `rejected` folder.
    #[serde(default)]
    pub trusted_clients: Vec<PathBuf>,
    /// The namespace URI of the plant's nodes; `urn:vigie:<plant folder>` by default.
    #[serde(default)]
    pub namespace: Option<String>,
}

/// The name of the anonymous identity in `plc_user`.
pub const ANONYMOUS: &str = "anonymous";

/// True when `endpoint` (`opc.tcp://HOST:PORT/…`) names a loopback host.
pub fn endpoint_is_loopback(endpoint: &str) -> bool {
    let host = endpoint
        .strip_prefix("opc.tcp://")
        .unwrap_or(endpoint)
        .split('/')
        .next()
        .unwrap_or("");
    let host = host
        .rsplit_once(':')
        .map_or(host, |(h, _)| h)
        .trim_start_matches('[')
        .trim_end_matches(']');
    host == "localhost" || host.parse::<IpAddr>().is_ok_and(|ip| ip.is_loopback())
}

impl OpcUaClientConfig {
    /// Resolves relative paths against `base`.
    pub fn resolve(&mut self, base: &Path) {
        for p in [
            &mut self.server_certificate,
            &mut self.password_file,
            &mut self.node_map,
        ]
        .into_iter()
        .flatten()
        {
            if p.is_relative() {
                *p = base.join(&*p);
            }
        }
    }

    /// Checks the section: errors and warnings.
    pub fn check(&self, file: &Path, text: &str, problems: &mut Vec<Problem>) {
        let at = |n: &str| Some(Location::of_nth(file, text, n, 0));
        if !self.endpoint.starts_with("opc.tcp://") {
            problems.push(Problem::error(
                codes::OPCUA_CONFIG.id,
                format!(
                    "`{}` is not an OPC UA endpoint: write `opc.tcp://HOST:PORT/`",
                    self.endpoint
                ),
                at("endpoint"),
            ));
        }
        check_none(self.security, &self.endpoint, at("endpoint"), problems);
        if self.user.is_some() != self.password_file.is_some() {
            problems.push(Problem::error(
                codes::OPCUA_CONFIG.id,
                "give `user` and `password_file` together (or neither, for an anonymous session)",
                at(if self.user.is_some() {
                    "user"
                } else {
                    "password_file"
                }),
            ));
        }
    }
}

impl OpcUaServerConfig {
    /// Resolves relative paths against `base`.
    pub fn resolve(&mut self, base: &Path) {
        for p in &mut self.trusted_clients {
            if p.is_relative() {
                *p = base.join(&*p);
            }
        }
    }

    /// Checks the section: errors and warnings.
    pub fn check(&self, file: &Path, text: &str, problems: &mut Vec<Problem>) {
        let at = |n: &str| Some(Location::of_nth(file, text, n, 0));
        if self.security.is_empty() {
            problems.push(Problem::error(
                codes::OPCUA_CONFIG.id,
                "`security` offers no endpoint: list at least one of None, Sign, SignAndEncrypt",
                at("security"),
            ));
        }
        for s in &self.security {
            check_none(*s, &self.bind.to_string(), at("security"), problems);
        }
        for u in &self.users {
            if u.name == ANONYMOUS || u.name.is_empty() {
                problems.push(Problem::error(
                    codes::OPCUA_CONFIG.id,
                    format!("`{}` cannot be a user name", u.name),
                    at(&format!("\"{}\"", u.name)),
                ));
            }
            if !u.password_hash.starts_with("$argon2") {
                problems.push(Problem::error(
                    codes::OPCUA_CONFIG.id,
                    format!(
                        "user `{}`: `password_hash` is not an argon2 PHC string (make one with `vigie opcua hash-password`)",
                        u.name
                    ),
                    at(&format!("\"{}\"", u.name)),
                ));
            }
        }
        if !self.anonymous && self.users.is_empty() {
            problems.push(Problem::error(
                codes::OPCUA_CONFIG.id,
                "nobody can open a session: add `users` or `anonymous: true`",
                at("OpcUa"),
            ));
        }
        match self.plc_user.as_deref() {
            Some(ANONYMOUS) if !self.anonymous => problems.push(Problem::error(
                codes::OPCUA_CONFIG.id,
                "`plc_user: \"anonymous\"` needs `anonymous: true`",
                at("plc_user"),
            )),
            Some(u) if u != ANONYMOUS && !self.users.iter().any(|x| x.name == u) => {
                problems.push(Problem::error(
                    codes::OPCUA_CONFIG.id,
                    format!("`plc_user` `{u}` is not one of the `users`"),
                    at("plc_user"),
                ));
            }
            _ => {}
        }
    }
}

/// Security None: a warning on loopback, an error elsewhere.
fn check_none(
    security: Security,
    address: &str,
    at: Option<Location>,
    problems: &mut Vec<Problem>,
) {
    if security != Security::None {
        return;
    }
    let loopback = endpoint_is_loopback(address);
    let message = format!(
        "OPC UA security None on {address}: messages are neither signed nor encrypted{}",
        if loopback {
            "; accepted on loopback only, for tests"
        } else {
            ", refused outside loopback: use Sign or SignAndEncrypt"
        }
    );
    problems.push(if loopback {
        Problem::warning(codes::OPCUA_SECURITY_NONE.id, message, at)
    } else {
        Problem::error(codes::OPCUA_SECURITY_NONE.id, message, at)
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_endpoints_are_told_apart() {
        for (e, yes) in [
            ("opc.tcp://127.0.0.1:4840/", true),
            ("opc.tcp://localhost:4840", true),
            ("opc.tcp://[::1]:4840/x", true),
            ("127.0.0.1:4840", true),
            ("opc.tcp://192.168.0.10:4840/", false),
            ("opc.tcp://plc.example:4840/", false),
        ] {
            assert_eq!(endpoint_is_loopback(e), yes, "{e}");
        }
    }

    fn problems(text: &str) -> (Vec<String>, Vec<String>) {
        let file = Path::new("g.ron");
        match crate::live::config::GatewayConfig::from_ron(text, file) {
            Ok(c) => (
                Vec::new(),
                c.warnings.iter().map(|w| format!("{w}")).collect(),
            ),
            Err(e) => (e.iter().map(|p| format!("{p}")).collect(), Vec::new()),
        }
    }

    #[test]
    fn security_none_is_a_warning_on_loopback_and_an_error_elsewhere() {
        let (errors, warnings) = problems(
            "Gateway(mode: Monitor, plant: \".\",\n client: OpcUa(endpoint: \"opc.tcp://127.0.0.1:4840/\", security: None))",
        );
        assert!(errors.is_empty(), "{errors:?}");
        assert!(
            warnings.len() == 1
                && warnings[0].contains("V1604")
                && warnings[0].contains("g.ron:2:"),
            "{warnings:?}"
        );
        let (errors, _) = problems(
            "Gateway(mode: Monitor, plant: \".\",\n client: OpcUa(endpoint: \"opc.tcp://10.0.0.5:4840/\", security: None))",
        );
        assert!(
            errors
                .iter()
                .any(|e| e.contains("error[V1604]") && e.contains("refused outside loopback")),
            "{errors:?}"
        );
        let (errors, _) = problems(
            "Gateway(mode: Emulator, plant: \".\",\n server: OpcUa(bind: \"0.0.0.0:4840\", security: [None], anonymous: true))",
        );
        assert!(
            errors.iter().any(|e| e.contains("error[V1604]")),
            "{errors:?}"
        );
    }

    #[test]
    fn impossible_users_and_writers_are_refused_with_their_place() {
        for (section, says) in [
            (
                "client: OpcUa(endpoint: \"opc.tcp://127.0.0.1:1/\", user: \"u\")",
                "together",
            ),
            (
                "client: OpcUa(endpoint: \"http://127.0.0.1:1/\")",
                "not an OPC UA endpoint",
            ),
            (
                "server: OpcUa(users: [(name: \"plc\", password_hash: \"secret\")], plc_user: \"plc\")",
                "not an argon2 PHC string",
            ),
            (
                "server: OpcUa(users: [(name: \"plc\", password_hash: \"$argon2id$x\")], plc_user: \"other\")",
                "is not one of the `users`",
            ),
            (
                "server: OpcUa(plc_user: \"anonymous\", users: [(name: \"a\", password_hash: \"$argon2id$x\")])",
                "needs `anonymous: true`",
            ),
            ("server: OpcUa()", "nobody can open a session"),
            (
                "server: OpcUa(security: [], anonymous: true)",
                "offers no endpoint",
            ),
        ] {
            let mode = if section.starts_with("client") {
                "Monitor"
            } else {
                "Emulator"
            };
            let (errors, _) =
                problems(&format!("Gateway(mode: {mode}, plant: \".\",\n {section})"));
            assert!(
                errors
                    .iter()
                    .any(|e| e.contains(says) && e.contains("V1605") && e.contains("g.ron:")),
                "{section}: {errors:?}"
            );
        }
    }
}
