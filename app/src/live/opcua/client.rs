//! The OPC UA client Vigie is to the plant (gateway) or to the monitored PLC (monitor),
//! on async-opcua: the same contract as the Modbus client (`super::super::modbus`).
//! It reads the node map's nodes when due, stamps every value with the time it was
//! sampled, reconnects with backoff, and never fails the caller.
//!
//! - **Reads** are cyclic Read requests with `maxAge = 0` (the server reads its source
//!   for the request). A value is stamped with the time the request was sent, as a
//!   Modbus value, or with `timestamps: Source` by its SourceTimestamp (else its
//!   ServerTimestamp) on Vigie's clock, never later than the request: the age at the
//!   source, for servers that stamp every sample. A value whose status is not Good, or
//!   that is not a Boolean, is not taken: it ages.
//! - **Connection**: the endpoint matching the configured security (Basic256Sha256
//!   Sign or SignAndEncrypt, or None on loopback), the user's name and password or
//!   anonymous; the client's certificate is created on first start in the PKI folder;
//!   the server's certificate must be trusted (`server_certificate`, or moved from
//!   `rejected` to `trusted`). Then every node of the map is resolved (namespace URIs
//!   through the server's namespace array, browse paths translated) and its value
//!   checked to be a Boolean: a map that does not fit the server refuses the
//!   connection, one V1603 line per node with its place in the map file.
//! - The session's own reconnection is off: a lost session is dropped and reopened
//!   by the link's backoff, as a Modbus connection is.

use super::super::link::{ClientStatus, Reconnect};
use super::pki;
use opcua::client::{ClientBuilder, IdentityToken, Session};
use opcua::crypto::SecurityPolicy;
use opcua::types::{
    AttributeId, BrowsePath, DataValue, DateTime, MessageSecurityMode, NodeId, ObjectId,
    QualifiedName, ReadValueId, ReferenceTypeId, RelativePath, RelativePathElement, StatusCode,
    TimestampsToReturn, Variant, WriteValue,
};
use std::sync::Arc;
use std::time::Duration;
use vigie_core::diag::codes;
use vigie_core::live::age::AgedBits;
use vigie_core::live::nodemap::{Identifier, MappedNode, Namespace, NodeMap, NodeRef};
use vigie_core::live::opcua::{OpcUaClientConfig, Security, Timestamps};
use vigie_core::{Bits, Millis};

/// An open session and the nodes resolved on it.
struct Open {
    session: Arc<Session>,
    event_loop: tokio::task::JoinHandle<StatusCode>,
    inputs: Vec<NodeId>,
    outputs: Vec<NodeId>,
}

impl Drop for Open {
    fn drop(&mut self) {
        self.event_loop.abort();
    }
}

/// The session and the poll schedule.
pub(crate) struct Link {
    config: OpcUaClientConfig,
    map: NodeMap,
    with_outputs: bool,
    pki: std::path::PathBuf,
    open: Option<Open>,
    last_poll: Option<Millis>,
    failing: Vec<bool>,
    link: Reconnect,
    /// Vigie's clock (`Millis` since the run's start) against the wall clock of the
    /// timestamps: the wall time of `Millis::ZERO`, in 100 ns ticks.
    epoch_ticks: i64,
    clock: std::time::Instant,
}

/// Ticks (100 ns) per millisecond.
const TICKS_PER_MS: i64 = 10_000;

impl Link {
    /// A client for `map`; `pki` holds its certificate and the trusted ones.
    pub(crate) fn new(
        config: OpcUaClientConfig,
        map: NodeMap,
        with_outputs: bool,
        pki: std::path::PathBuf,
        clock: std::time::Instant,
    ) -> Self {
        let since = i64::try_from(clock.elapsed().as_nanos() / 100).unwrap_or(0);
        let n = map.inputs.len() + map.outputs.len();
        Self {
            link: Reconnect::new(config.backoff_initial_ms, config.backoff_max_ms),
            config,
            map,
            with_outputs,
            pki,
            open: None,
            last_poll: None,
            failing: vec![false; n],
            epoch_ticks: DateTime::now().ticks() - since,
            clock,
        }
    }

    pub(crate) fn peer(&self) -> &str {
        &self.config.endpoint
    }

    pub(crate) fn status(&self) -> &ClientStatus {
        &self.link.status
    }

    pub(crate) fn is_connected(&self) -> bool {
        self.open.is_some()
    }

    fn timeout(&self) -> Duration {
        Duration::from_millis(self.config.timeout_ms.max(1))
    }

    /// Opens a session and resolves the map on it, when the backoff allows.
    async fn ensure_connected(&mut self, now: Millis) -> bool {
        if self.open.is_some() {
            return true;
        }
        if !self.link.may_try(now) {
            return false;
        }
        // A secure handshake (RSA) takes longer than one request.
        let limit = self.timeout() * 10;
        match tokio::time::timeout(limit, self.connect()).await {
            Ok(Ok(open)) => {
                tracing::info!(peer = %self.peer(), "connected ({})", self.config.security);
                self.open = Some(open);
                self.last_poll = None;
                self.link.connected();
                true
            }
            Ok(Err(why)) => {
                self.retry_later(now, &why);
                false
            }
            Err(_) => {
                self.retry_later(
                    now,
                    &format!("cannot connect: no session in {} ms", limit.as_millis()),
                );
                false
            }
        }
    }

    async fn connect(&self) -> Result<Open, String> {
        let peer = self.peer().to_string();
        let mut client = ClientBuilder::new()
            .application_name("Vigie")
            .application_uri(pki::APPLICATION_URI)
            .product_uri(pki::PRODUCT_URI)
            .pki_dir(&self.pki)
            .create_sample_keypair(true)
            .trust_server_certs(false)
            .session_retry_limit(0)
            .session_timeout(60_000)
            .request_timeout(self.timeout())
            .client()
            .map_err(|e| format!("cannot set up the OPC UA client: {}", e.join("; ")))?;
        if let Some(cert) = &self.config.server_certificate {
            pki::trust(&self.pki, cert).map_err(|e| format!("{e}"))?;
        }
        let (policy, mode) = match self.config.security {
            Security::None => (SecurityPolicy::None, MessageSecurityMode::None),
            Security::Sign => (SecurityPolicy::Basic256Sha256, MessageSecurityMode::Sign),
            Security::SignAndEncrypt => (
                SecurityPolicy::Basic256Sha256,
                MessageSecurityMode::SignAndEncrypt,
            ),
        };
        let identity = match (&self.config.user, &self.config.password_file) {
            (Some(user), Some(file)) => {
                IdentityToken::new_user_name(user.clone(), pki::read_password(file)?)
            }
            _ => IdentityToken::Anonymous,
        };
        let (session, event_loop) = client
            .connect_to_matching_endpoint((peer.as_str(), policy.to_str(), mode), identity)
            .await
            .map_err(|e| {
                format!(
                    "cannot open a session ({}): {}",
                    self.config.security,
                    pki::describe(&e.to_string(), &self.pki)
                )
            })?;
        session.disable_reconnects();
        let mut event_loop = event_loop.spawn();
        tokio::select! {
            connected = session.wait_for_connection() => {
                if !connected {
                    return Err("the server refused the session".to_string());
                }
            }
            ended = &mut event_loop => {
                let why = match ended {
                    Ok(code) => pki::describe(&format!("{code}"), &self.pki),
                    Err(e) => e.to_string(),
                };
                return Err(format!("cannot open a session ({}): {why}", self.config.security));
            }
        }
        let mut open = Open {
            session,
            event_loop,
            inputs: Vec::new(),
            outputs: Vec::new(),
        };
        self.resolve(&mut open).await?;
        Ok(open)
    }

    /// Resolves every node of the map on the open session and checks it is a Boolean.
    async fn resolve(&self, open: &mut Open) -> Result<(), String> {
        let session = &open.session;
        let namespaces = session
            .read_namespace_array()
            .await
            .map_err(|e| format!("cannot read the server's namespace array: {e}"))?;
        let mut problems = Vec::new();
        let mut ids = Vec::new();
        let entries: Vec<&MappedNode> = self.map.inputs.iter().chain(&self.map.outputs).collect();
        let mut paths = Vec::new();
        for (k, m) in entries.iter().enumerate() {
            match node_id(&m.node, &namespaces) {
                Ok(Resolved::Id(id)) => ids.push(Some(id)),
                Ok(Resolved::Path(p)) => {
                    ids.push(None);
                    paths.push((k, p));
                }
                Err(why) => {
                    ids.push(None);
                    problems.push((k, why));
                }
            }
        }
        if !paths.is_empty() {
            let asked: Vec<BrowsePath> = paths.iter().map(|(_, p)| p.clone()).collect();
            let results = session
                .translate_browse_paths_to_node_ids(&asked)
                .await
                .map_err(|e| format!("cannot translate the browse paths: {e}"))?;
            for ((k, _), r) in paths.iter().zip(results) {
                match r.targets.as_ref().and_then(|t| t.first()) {
                    Some(t) if r.status_code.is_good() => {
                        if let Some(slot) = ids.get_mut(*k) {
                            *slot = Some(t.target_id.node_id.clone());
                        }
                    }
                    _ => problems.push((
                        *k,
                        format!("the browse path does not resolve ({})", r.status_code),
                    )),
                }
            }
        }
        let to_read: Vec<(usize, ReadValueId)> = ids
            .iter()
            .enumerate()
            .filter_map(|(k, id)| id.clone().map(|id| (k, ReadValueId::from(id))))
            .collect();
        let values = session
            .read(
                &to_read.iter().map(|(_, r)| r.clone()).collect::<Vec<_>>(),
                TimestampsToReturn::Neither,
                0.0,
            )
            .await
            .map_err(|e| format!("cannot read the mapped nodes: {e}"))?;
        for ((k, _), v) in to_read.iter().zip(values) {
            let status = v.status.unwrap_or(StatusCode::Good);
            if !status.is_good() {
                problems.push((
                    *k,
                    format!("unknown to the server or unreadable ({status})"),
                ));
            } else if !matches!(v.value, Some(Variant::Boolean(_))) {
                problems.push((
                    *k,
                    format!(
                        "its value is not a Boolean ({})",
                        v.value
                            .as_ref()
                            .map_or("no value".to_string(), |x| format!("{:?}", x.type_id()))
                    ),
                ));
            }
        }
        if !problems.is_empty() {
            return Err(self.misfits(&entries, &problems));
        }
        let n_in = self.map.inputs.len();
        let ids: Vec<NodeId> = ids.into_iter().flatten().collect();
        open.inputs = ids.get(..n_in).map(<[NodeId]>::to_vec).unwrap_or_default();
        open.outputs = ids.get(n_in..).map(<[NodeId]>::to_vec).unwrap_or_default();
        Ok(())
    }

    /// The nodes that do not fit the server, one V1603 line each with its place in the
    /// map file.
    fn misfits(&self, entries: &[&MappedNode], problems: &[(usize, String)]) -> String {
        let lines: Vec<String> = problems
            .iter()
            .map(|(k, why)| {
                let m = entries.get(*k);
                let at = m
                    .and_then(|m| m.at.as_ref())
                    .map_or(String::new(), |l| format!("{l}: "));
                format!(
                    "{at}error[{}]: `{}` at {}: node {} {why}",
                    codes::OPCUA_NODE_UNKNOWN.id,
                    m.map_or("?", |m| m.signal.as_str()),
                    self.peer(),
                    m.map_or(String::new(), |m| m.node.to_string()),
                )
            })
            .collect();
        format!(
            "the node map does not fit the server:\n{}",
            lines.join("\n")
        )
    }

    fn retry_later(&mut self, now: Millis, why: &str) {
        let peer = self.config.endpoint.clone();
        self.link.retry_later(&peer, now, why);
    }

    fn drop_session(&mut self, now: Millis, why: &str) {
        tracing::warn!(peer = %self.peer(), "{why}; session dropped");
        self.open = None;
        self.link.dropped(now);
    }

    /// The time on Vigie's clock of an OPC UA timestamp.
    fn on_clock(&self, t: &DateTime) -> Millis {
        let ms = (t.ticks() - self.epoch_ticks) / TICKS_PER_MS;
        Millis(u64::try_from(ms).unwrap_or(0))
    }

    /// Reads the inputs (and the outputs, monitor) when due; true when all were read.
    pub(crate) async fn poll(
        &mut self,
        now: Millis,
        inputs: &mut AgedBits,
        outputs: &mut AgedBits,
    ) -> bool {
        if !self.ensure_connected(now).await {
            return false;
        }
        let period = self.map.fastest_poll();
        if self
            .last_poll
            .is_some_and(|t| now.saturating_sub(t) < period.saturating_sub(Millis(1)))
        {
            return true;
        }
        let Some(open) = self.open.as_ref() else {
            return false;
        };
        let mut nodes: Vec<ReadValueId> =
            open.inputs.iter().cloned().map(ReadValueId::from).collect();
        if self.with_outputs {
            nodes.extend(open.outputs.iter().cloned().map(ReadValueId::from));
        }
        let sent = self.clock_now();
        let answer = tokio::time::timeout(
            self.timeout(),
            open.session.read(&nodes, TimestampsToReturn::Both, 0.0),
        )
        .await;
        let values = match answer {
            Ok(Ok(v)) if v.len() == nodes.len() => v,
            Ok(Ok(v)) => {
                self.drop_session(
                    now,
                    &format!(
                        "read {} nodes, the server answered {}",
                        nodes.len(),
                        v.len()
                    ),
                );
                return false;
            }
            Ok(Err(e)) => {
                self.drop_session(now, &format!("read failed: {e}"));
                return false;
            }
            Err(_) => {
                self.drop_session(
                    now,
                    &format!("read timed out after {} ms", self.config.timeout_ms),
                );
                return false;
            }
        };
        self.last_poll = Some(now);
        let n_in = inputs.len();
        let mut all_ok = true;
        for (k, v) in values.iter().enumerate() {
            let taken = match self.sample(v, sent) {
                Some((value, at)) => {
                    if k < n_in {
                        inputs.set(k, value, at);
                    } else {
                        outputs.set(k - n_in, value, at);
                    }
                    true
                }
                None => false,
            };
            if let Some(f) = self.failing.get_mut(k)
                && *f == taken
            {
                *f = !taken;
                if taken {
                    tracing::info!(peer = %self.config.endpoint, "node #{k} read again");
                } else {
                    tracing::warn!(
                        peer = %self.config.endpoint,
                        "node #{k}: status {}, value {:?}: not taken, it ages",
                        v.status.unwrap_or(StatusCode::Good),
                        v.value
                    );
                }
            }
            all_ok &= taken;
        }
        if !all_ok {
            self.link.status.exceptions += 1;
        } else {
            self.link.answered(now);
        }
        all_ok
    }

    fn clock_now(&self) -> Millis {
        Millis(u64::try_from(self.clock.elapsed().as_millis()).unwrap_or(u64::MAX))
    }

    /// A read value and when it was sampled, if it is a Good Boolean.
    fn sample(&self, v: &DataValue, sent: Millis) -> Option<(bool, Millis)> {
        if !v.status.unwrap_or(StatusCode::Good).is_good() {
            return None;
        }
        let Some(Variant::Boolean(b)) = v.value else {
            return None;
        };
        let sampled = match self.config.timestamps {
            Timestamps::Request => sent,
            Timestamps::Source => v
                .source_timestamp
                .as_ref()
                .or(v.server_timestamp.as_ref())
                .filter(|t| !t.is_null())
                .map_or(sent, |t| self.on_clock(t).min(sent)),
        };
        Some((b, sampled))
    }

    /// Writes every output (connecting first when the backoff allows); `Ok` when the
    /// server accepted every value, else why not.
    pub(crate) async fn write(&mut self, now: Millis, values: &Bits) -> Result<(), String> {
        if !self.ensure_connected(now).await {
            return Err(format!(
                "{}: not connected (next attempt at {})",
                self.peer(),
                self.link.next_attempt
            ));
        }
        let Some(open) = self.open.as_ref() else {
            return Err(format!("{}: not connected", self.peer()));
        };
        let writes: Vec<WriteValue> = open
            .outputs
            .iter()
            .enumerate()
            .map(|(k, id)| WriteValue {
                node_id: id.clone(),
                attribute_id: AttributeId::Value as u32,
                index_range: Default::default(),
                value: DataValue::value_only(Variant::Boolean(values.get(k))),
            })
            .collect();
        let answer = tokio::time::timeout(self.timeout(), open.session.write(&writes)).await;
        match answer {
            Ok(Ok(codes)) if codes.len() == writes.len() && codes.iter().all(|c| c.is_good()) => {
                Ok(())
            }
            Ok(Ok(codes)) => {
                self.link.status.exceptions += 1;
                let why = format!(
                    "{}: the server refused the outputs ({})",
                    self.peer(),
                    codes
                        .iter()
                        .map(|c| c.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                );
                tracing::warn!("{why}");
                Err(why)
            }
            Ok(Err(e)) => {
                let why = format!("{}: write failed: {e}", self.peer());
                self.drop_session(now, &why);
                Err(why)
            }
            Err(_) => {
                let why = format!(
                    "{}: write timed out after {} ms",
                    self.peer(),
                    self.config.timeout_ms
                );
                self.drop_session(now, &why);
                Err(why)
            }
        }
    }
}

enum Resolved {
    Id(NodeId),
    Path(BrowsePath),
}

/// The server's node id of a map entry, or the browse path to translate.
fn node_id(node: &NodeRef, namespaces: &opcua::types::NamespaceMap) -> Result<Resolved, String> {
    let index = |ns: &Namespace| match ns {
        Namespace::Index(i) => Ok(*i),
        Namespace::Uri(u) => namespaces
            .get_index(u)
            .ok_or_else(|| format!("is in namespace {u}, which the server does not have")),
    };
    match node {
        NodeRef::Id {
            namespace,
            identifier,
        } => {
            let ns = index(namespace)?;
            Ok(Resolved::Id(match identifier {
                Identifier::Numeric(n) => NodeId::new(ns, *n),
                Identifier::String(s) => NodeId::new(ns, s.clone()),
                Identifier::Guid(g) => NodeId::new(
                    ns,
                    opcua::types::Guid::from_str(g).map_err(|_| format!("bad GUID {g}"))?,
                ),
                Identifier::Opaque(b) => NodeId::new(
                    ns,
                    opcua::types::ByteString::from_base64(b)
                        .ok_or_else(|| format!("bad base64 {b}"))?,
                ),
            }))
        }
        NodeRef::Path(elements) => {
            let mut rel = Vec::new();
            for (ns, name) in elements {
                rel.push(RelativePathElement {
                    reference_type_id: ReferenceTypeId::HierarchicalReferences.into(),
                    is_inverse: false,
                    include_subtypes: true,
                    target_name: QualifiedName::new(index(ns)?, name.as_str()),
                });
            }
            Ok(Resolved::Path(BrowsePath {
                starting_node: ObjectId::ObjectsFolder.into(),
                relative_path: RelativePath {
                    elements: Some(rel),
                },
            }))
        }
    }
}

use std::str::FromStr as _;
