//! The OPC UA server Vigie is to a PLC (gateway mode) or to a soft-PLC (emulator mode),
//! on async-opcua: it answers from the same [`Shared`] image as the Modbus server.
//!
//! Address space: a folder `Objects/<plant name>` in the plant's namespace
//! (`urn:vigie:<plant folder>` unless `namespace` says otherwise) with one Boolean
//! variable per plant signal, node id `s=<signal>`: the inputs (read-only for
//! everyone) and the outputs (writable by `plc_user` alone). Reads answer from the
//! image at the moment of the read (server and source timestamps: now), so a client
//! sees the value the cycle served last, never a cached one.
//!
//! Security: the endpoints listed (None only on loopback; Basic256Sha256 Sign and
//! SignAndEncrypt), Vigie's certificate created on first start in the PKI folder,
//! client certificates trusted explicitly (`trusted_clients`, else refused and kept in
//! `rejected/`), user names checked against argon2 hashes, anonymous sessions only when
//! allowed. The PLC's liveness is its own accepted writes of outputs.

use super::super::modbus::server::{Shared, SharedImage};
use super::pki;
use argon2::PasswordVerifier as _;
use opcua::crypto::SecurityPolicy;
use opcua::nodes::{AccessLevel, Variable};
use opcua::server::authenticator::{AuthManager, DefaultAuthenticator, Password, UserToken};
use opcua::server::diagnostics::NamespaceMetadata;
use opcua::server::node_manager::memory::{SimpleNodeManager, simple_node_manager};
use opcua::server::{ANONYMOUS_USER_TOKEN_ID, ServerBuilder, ServerEndpoint, ServerUserToken};
use opcua::types::{
    DataTypeId, DataValue, DateTime, MessageSecurityMode, NodeId, ObjectId, StatusCode,
    UserTokenPolicy, Variant,
};
use std::collections::HashSet;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Instant;
use vigie_core::live::opcua::{ANONYMOUS, OpcUaServerConfig, Security};

use super::super::cycle::lock;

/// A running server; stopped when dropped.
pub(crate) struct ServerHandle {
    /// Its endpoint URL.
    pub(crate) endpoint: String,
    /// The address it listens on.
    pub(crate) local: SocketAddr,
    handle: opcua::server::ServerHandle,
    task: tokio::task::JoinHandle<()>,
}

impl Drop for ServerHandle {
    fn drop(&mut self) {
        self.handle.cancel();
        self.task.abort();
    }
}

/// What the server serves: the plant's name, its namespace and its signals.
pub(crate) struct AddressSpace<'a> {
    /// The plant's name (the folder's browse name).
    pub(crate) plant: &'a str,
    /// The namespace URI.
    pub(crate) namespace: &'a str,
    /// Input signal ids, in plant order.
    pub(crate) inputs: Vec<String>,
    /// Output signal ids, in plant order.
    pub(crate) outputs: Vec<String>,
}

/// Who may do what: users by argon2 hash, the PLC's identity, the nodes it may write.
struct Access {
    users: std::collections::BTreeMap<String, String>,
    anonymous: bool,
    plc: Option<String>,
    /// The output nodes, filled in once the namespace index is known.
    writable: Arc<std::sync::RwLock<HashSet<NodeId>>>,
    policies: DefaultAuthenticator,
}

#[async_trait::async_trait]
impl AuthManager for Access {
    async fn authenticate_anonymous_token(
        &self,
        endpoint: &ServerEndpoint,
    ) -> Result<(), opcua::types::Error> {
        if self.anonymous && endpoint.user_token_ids.contains(ANONYMOUS_USER_TOKEN_ID) {
            Ok(())
        } else {
            Err(opcua::types::Error::new(
                StatusCode::BadIdentityTokenRejected,
                "anonymous sessions are not allowed",
            ))
        }
    }

    async fn authenticate_username_identity_token(
        &self,
        _endpoint: &ServerEndpoint,
        username: &str,
        password: &Password,
    ) -> Result<UserToken, opcua::types::Error> {
        let refused = || {
            tracing::warn!("OPC UA: user `{username}` refused (unknown user or wrong password)");
            opcua::types::Error::new(
                StatusCode::BadUserAccessDenied,
                format!("cannot authenticate `{username}`"),
            )
        };
        let hash = self.users.get(username).ok_or_else(refused)?;
        let parsed = argon2::password_hash::PasswordHash::new(hash).map_err(|_| refused())?;
        argon2::Argon2::default()
            .verify_password(password.get().as_bytes(), &parsed)
            .map_err(|_| refused())?;
        Ok(UserToken(username.to_string()))
    }

    fn effective_user_access_level(
        &self,
        token: &UserToken,
        level: AccessLevel,
        node_id: &NodeId,
    ) -> AccessLevel {
        if !self.writable.read().is_ok_and(|w| w.contains(node_id)) {
            return level - AccessLevel::CURRENT_WRITE;
        }
        let is_plc = match self.plc.as_deref() {
            Some(ANONYMOUS) => token.is_anonymous(),
            Some(plc) => token.0 == plc && !token.is_anonymous(),
            None => false,
        };
        if is_plc {
            level
        } else {
            level - AccessLevel::CURRENT_WRITE
        }
    }

    fn user_token_policies(&self, endpoint: &ServerEndpoint) -> Vec<UserTokenPolicy> {
        self.policies.user_token_policies(endpoint)
    }
}

fn policy(security: Security) -> (SecurityPolicy, MessageSecurityMode, &'static str) {
    match security {
        Security::None => (SecurityPolicy::None, MessageSecurityMode::None, "none"),
        Security::Sign => (
            SecurityPolicy::Basic256Sha256,
            MessageSecurityMode::Sign,
            "basic256sha256_sign",
        ),
        Security::SignAndEncrypt => (
            SecurityPolicy::Basic256Sha256,
            MessageSecurityMode::SignAndEncrypt,
            "basic256sha256_sign_encrypt",
        ),
    }
}

/// Binds and starts a server over `shared`, serving `space`; certificates in `pki`.
pub(crate) async fn start(
    config: &OpcUaServerConfig,
    space: &AddressSpace<'_>,
    shared: SharedImage,
    pki_dir: &std::path::Path,
) -> anyhow::Result<ServerHandle> {
    for u in &config.users {
        argon2::password_hash::PasswordHash::new(&u.password_hash).map_err(|e| {
            anyhow::anyhow!(
                "error[{}]: user `{}`: `password_hash` is not an argon2 PHC string ({e}); make one with `vigie opcua hash-password`",
                vigie_core::diag::codes::OPCUA_CONFIG.id,
                u.name
            )
        })?;
    }
    pki::own_certificate(pki_dir)?;
    for cert in &config.trusted_clients {
        pki::trust(pki_dir, cert)?;
    }
    let listener = tokio::net::TcpListener::bind(config.bind)
        .await
        .map_err(|e| anyhow::anyhow!("cannot listen on {}: {e}", config.bind))?;
    let local = listener.local_addr()?;
    // Bound to every interface, the endpoint names the machine (its certificate
    // carries the host names); else the address bound.
    let host = if local.ip().is_unspecified() {
        opcua::crypto::X509Data::computer_hostnames()
            .into_iter()
            .next()
            .unwrap_or_else(|| "localhost".to_string())
    } else {
        local.ip().to_string()
    };
    let endpoint = format!("opc.tcp://{host}:{}/", local.port());
    let mut token_ids: Vec<String> = config.users.iter().map(|u| u.name.clone()).collect();
    if config.anonymous {
        token_ids.push(ANONYMOUS_USER_TOKEN_ID.to_string());
    }
    let ids: Vec<&str> = token_ids.iter().map(String::as_str).collect();
    let mut builder = ServerBuilder::new()
        .application_name("Vigie")
        .application_uri(pki::APPLICATION_URI)
        .product_uri(pki::PRODUCT_URI)
        .pki_dir(pki_dir)
        .create_sample_keypair(true)
        .trust_client_certs(false)
        .host(host)
        .port(local.port())
        .discovery_urls(vec![endpoint.clone()])
        .with_node_manager(simple_node_manager(
            NamespaceMetadata {
                namespace_uri: space.namespace.to_string(),
                ..Default::default()
            },
            "vigie",
        ));
    for u in &config.users {
        builder =
            builder.add_user_token(&u.name, ServerUserToken::user_pass(&u.name, &String::new()));
    }
    for s in &config.security {
        let (p, m, id) = policy(*s);
        builder = builder.add_endpoint(id, ("/", p, m, ids.as_slice()));
    }
    let policies = DefaultAuthenticator::new(builder.config().user_tokens.clone());
    // The node ids need the namespace index, known once the server is built; the
    // writable set is filled before the server runs.
    let writable = Arc::new(std::sync::RwLock::new(HashSet::new()));
    let access = Arc::new(Access {
        users: config
            .users
            .iter()
            .map(|u| (u.name.clone(), u.password_hash.clone()))
            .collect(),
        anonymous: config.anonymous,
        plc: config.plc_user.clone(),
        writable: Arc::clone(&writable),
        policies,
    });
    let (server, handle) = builder
        .with_authenticator(access)
        .build()
        .map_err(|e| anyhow::anyhow!("cannot build the OPC UA server: {e}"))?;
    let manager = handle
        .node_managers()
        .get_of_type::<SimpleNodeManager>()
        .ok_or_else(|| anyhow::anyhow!("the OPC UA node manager is missing"))?;
    let ns = handle
        .get_namespace_index(space.namespace)
        .ok_or_else(|| anyhow::anyhow!("namespace {} not registered", space.namespace))?;
    let outputs = populate(&manager, ns, space, &shared);
    if let Ok(mut w) = writable.write() {
        w.extend(outputs);
    }
    let task = tokio::spawn(async move {
        if let Err(e) = server.run_with(listener).await {
            tracing::error!("the OPC UA server on {local} stopped: {e}");
        }
    });
    Ok(ServerHandle {
        endpoint,
        local,
        handle,
        task,
    })
}

/// Adds the plant's folder and variables, with callbacks reading and writing the
/// image; returns the output nodes (the writable ones).
fn populate(
    manager: &SimpleNodeManager,
    ns: u16,
    space: &AddressSpace<'_>,
    shared: &SharedImage,
) -> Vec<NodeId> {
    let folder = NodeId::new(ns, space.plant.to_string());
    let mut outputs = Vec::new();
    {
        let mut a = manager.address_space().write();
        a.add_folder(
            &folder,
            opcua::types::QualifiedName::new(ns, space.plant),
            space.plant,
            &ObjectId::ObjectsFolder.into(),
        );
        let mut vars = Vec::new();
        for (k, id) in space.inputs.iter().chain(&space.outputs).enumerate() {
            let node = NodeId::new(ns, id.clone());
            let mut v = Variable::new(
                &node,
                opcua::types::QualifiedName::new(ns, id.as_str()),
                id.as_str(),
                false,
            );
            v.set_data_type(DataTypeId::Boolean);
            if k >= space.inputs.len() {
                v.set_access_level(AccessLevel::CURRENT_READ | AccessLevel::CURRENT_WRITE);
                v.set_user_access_level(AccessLevel::CURRENT_READ | AccessLevel::CURRENT_WRITE);
                outputs.push(node);
            }
            vars.push(v);
        }
        a.add_variables(vars, &folder);
    }
    let n_in = space.inputs.len();
    for (k, id) in space.inputs.iter().chain(&space.outputs).enumerate() {
        let node = NodeId::new(ns, id.clone());
        let image = Arc::clone(shared);
        manager
            .inner()
            .add_read_callback(node.clone(), move |_, _, _| {
                let s = lock(&image);
                let value = if k < n_in {
                    s.inputs.get(k)
                } else {
                    s.outputs.get(k - n_in)
                };
                let now = DateTime::now();
                Ok(DataValue {
                    value: Some(Variant::Boolean(value)),
                    status: Some(StatusCode::Good),
                    source_timestamp: Some(now),
                    server_timestamp: Some(now),
                    ..Default::default()
                })
            });
        if k >= n_in {
            let image = Arc::clone(shared);
            manager.inner().add_write_callback(node, move |value, _| {
                let Some(Variant::Boolean(b)) = value.value else {
                    return StatusCode::BadTypeMismatch;
                };
                let mut s: std::sync::MutexGuard<'_, Shared> = lock(&image);
                s.outputs.set(k - n_in, b);
                s.plc_heard = Some(Instant::now());
                StatusCode::Good
            });
        }
    }
    outputs
}
