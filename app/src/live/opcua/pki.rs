//! Vigie's OPC UA certificates and the ones it trusts: a PKI folder in the async-opcua
//! layout (`own/cert.der`, `private/private.pem`, `trusted/`, `rejected/`), under the
//! run's state folder (`<state_dir>/pki`). Vigie's own certificate is created on first
//! start; a peer's certificate is trusted explicitly, never on first use: given in the
//! configuration (`server_certificate`, `trusted_clients`), or moved by hand from
//! `rejected/`, where async-opcua keeps every certificate it refused.

use opcua::crypto::{CertificateStore, X509};
use std::path::{Path, PathBuf};

/// The application URI in Vigie's certificate.
pub(crate) const APPLICATION_URI: &str = "urn:vigie:console";
/// The product URI.
pub(crate) const PRODUCT_URI: &str = "urn:vigie";

/// The PKI folder of a run whose state folder is `state_dir`.
pub(crate) fn folder(state_dir: &Path) -> PathBuf {
    state_dir.join("pki")
}

/// Reads a certificate (DER or PEM).
fn read(cert: &Path) -> anyhow::Result<X509> {
    CertificateStore::read_cert(cert)
        .map_err(|e| anyhow::anyhow!("cannot read the certificate {}: {e}", cert.display()))
}

/// Trusts `cert`: a copy in `pki/trusted/` under the name async-opcua looks for, and
/// out of `pki/rejected/` (a certificate there is refused whatever `trusted/` holds).
pub(crate) fn trust(pki: &Path, cert: &Path) -> anyhow::Result<PathBuf> {
    let x509 = read(cert)?;
    let name = CertificateStore::cert_file_name(&x509);
    let trusted = pki.join("trusted");
    std::fs::create_dir_all(&trusted)
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", trusted.display()))?;
    std::fs::create_dir_all(pki.join("rejected"))
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", pki.join("rejected").display()))?;
    let der = x509
        .to_der()
        .map_err(|e| anyhow::anyhow!("cannot encode {}: {e}", cert.display()))?;
    let target = trusted.join(&name);
    if std::fs::read(&target).ok().as_deref() != Some(der.as_slice()) {
        std::fs::write(&target, &der)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", target.display()))?;
    }
    let rejected = pki.join("rejected").join(&name);
    if rejected.exists() {
        std::fs::remove_file(&rejected)
            .map_err(|e| anyhow::anyhow!("cannot remove {}: {e}", rejected.display()))?;
    }
    Ok(target)
}

/// Vigie's own certificate in `pki`, created (with its private key) when absent: its
/// path and SHA-1 thumbprint, for the peer's administrator to trust.
pub(crate) fn own_certificate(pki: &Path) -> anyhow::Result<(PathBuf, String)> {
    let store = CertificateStore::new(pki);
    let path = store.own_certificate_path();
    if !path.exists() {
        let description = opcua::types::ApplicationDescription {
            application_uri: APPLICATION_URI.into(),
            product_uri: PRODUCT_URI.into(),
            application_name: opcua::types::LocalizedText::new("", "Vigie"),
            ..Default::default()
        };
        CertificateStore::create_certificate_and_key(
            &description.into(),
            true,
            &path,
            &store.own_private_key_path(),
        )
        .map_err(|e| {
            anyhow::anyhow!(
                "cannot create Vigie's certificate in {}: {e}",
                pki.display()
            )
        })?;
    }
    store
        .ensure_pki_path()
        .map_err(|e| anyhow::anyhow!("cannot create the PKI folder {}: {e}", pki.display()))?;
    let cert = read(&path)?;
    Ok((path, cert.thumbprint().as_hex_string()))
}

/// The first line of a password file.
pub(crate) fn read_password(file: &Path) -> Result<String, String> {
    let text = std::fs::read_to_string(file)
        .map_err(|e| format!("cannot read the password file {}: {e}", file.display()))?;
    Ok(text.lines().next().unwrap_or("").to_string())
}

/// An async-opcua error in words, with what to do about an untrusted certificate.
pub(crate) fn describe(error: &str, pki: &Path) -> String {
    let untrusted = [
        "BadCertificateUntrusted",
        "BadSecurityChecksFailed",
        "untrusted",
    ]
    .iter()
    .any(|k| error.contains(k));
    if untrusted {
        format!(
            "{error} (a certificate is not trusted: the peer's certificate, if refused here, is in {}; trust it with `server_certificate` in the configuration or by moving it to {}; Vigie's own certificate, {}, must be trusted by the peer)",
            pki.join("rejected").display(),
            pki.join("trusted").display(),
            pki.join("own/cert.der").display()
        )
    } else if error.contains("BadIdentityTokenRejected") || error.contains("BadUserAccessDenied") {
        format!("{error} (the user name or password was refused)")
    } else {
        error.to_string()
    }
}
