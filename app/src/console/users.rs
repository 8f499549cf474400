//! The console's user accounts: a name, a role and an argon2id password hash each, in
//! `users.ron` in the data folder (`vigie user add` writes it). No clear password is
//! ever stored or logged.

use argon2::Argon2;
use argon2::password_hash::{PasswordHash, PasswordHasher as _, PasswordVerifier as _, SaltString};
use password_hash::rand_core::OsRng;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use vigie_core::access::Role;

/// One account.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Account {
    /// Login name.
    pub name: String,
    /// Its role.
    pub role: Role,
    /// The argon2id hash in PHC format (`$argon2id$v=19$…`).
    pub hash: String,
}

/// Why an account operation failed.
#[derive(Debug, thiserror::Error)]
pub enum UsersError {
    /// The file cannot be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The accounts file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// The file does not parse.
    #[error("{path}:{line}:{column}: {message}")]
    Parse {
        /// The accounts file.
        path: PathBuf,
        /// Line.
        line: usize,
        /// Column.
        column: usize,
        /// The parser's message.
        message: String,
    },
    /// A bad name or password.
    #[error("{0}")]
    Invalid(String),
    /// Unknown user or wrong password (one message for both).
    #[error("unknown user or wrong password")]
    Refused,
}

/// The accounts of a data folder.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Users {
    /// The accounts, in file order.
    pub accounts: Vec<Account>,
}

impl Users {
    /// The accounts file of a data folder.
    pub fn path(data_dir: &Path) -> PathBuf {
        data_dir.join("users.ron")
    }

    /// Loads `users.ron` from `data_dir` (no file: no account).
    pub fn load(data_dir: &Path) -> Result<Self, UsersError> {
        let path = Self::path(data_dir);
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Self::default()),
            Err(source) => return Err(UsersError::Io { path, source }),
        };
        let accounts: Vec<Account> = ron::from_str(&text).map_err(|e| UsersError::Parse {
            path: path.clone(),
            line: e.span.start.line,
            column: e.span.start.col,
            message: e.code.to_string(),
        })?;
        Ok(Self { accounts })
    }

    /// Writes `users.ron` into `data_dir` (created if needed), through a temporary
    /// file renamed over the old one, so a crash never leaves half a file.
    pub fn save(&self, data_dir: &Path) -> Result<(), UsersError> {
        let path = Self::path(data_dir);
        let io = |source| UsersError::Io {
            path: path.clone(),
            source,
        };
        std::fs::create_dir_all(data_dir).map_err(io)?;
        let text = ron::ser::to_string_pretty(&self.accounts, ron::ser::PrettyConfig::default())
            .map_err(|e| UsersError::Invalid(e.to_string()))?;
        let tmp = data_dir.join("users.ron.tmp");
        std::fs::write(
            &tmp,
            format!("// Vigie console accounts: argon2id hashes, never a password.\n{text}\n"),
        )
        .map_err(io)?;
        std::fs::rename(&tmp, &path).map_err(io)
    }

    /// Adds or replaces the account `name` with `role` and the hash of `password`.
    pub fn set(&mut self, name: &str, role: Role, password: &str) -> Result<(), UsersError> {
        let name = name.trim();
        if name.is_empty() || name.chars().any(char::is_whitespace) {
            return Err(UsersError::Invalid(format!(
                "`{name}`: a user name is one word"
            )));
        }
        if password.chars().count() < 8 {
            return Err(UsersError::Invalid(
                "a password has at least 8 characters".into(),
            ));
        }
        let salt = SaltString::generate(&mut OsRng);
        let hash = Argon2::default()
            .hash_password(password.as_bytes(), &salt)
            .map_err(|e| UsersError::Invalid(e.to_string()))?
            .to_string();
        let account = Account {
            name: name.to_string(),
            role,
            hash,
        };
        match self.accounts.iter_mut().find(|a| a.name == name) {
            Some(a) => *a = account,
            None => self.accounts.push(account),
        }
        Ok(())
    }

    /// The role of `name` when `password` is its password.
    pub fn verify(&self, name: &str, password: &str) -> Result<Role, UsersError> {
        let account = self
            .accounts
            .iter()
            .find(|a| a.name == name.trim())
            .ok_or(UsersError::Refused)?;
        let hash = PasswordHash::new(&account.hash).map_err(|_| UsersError::Refused)?;
        Argon2::default()
            .verify_password(password.as_bytes(), &hash)
            .map_err(|_| UsersError::Refused)?;
        Ok(account.role)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accounts_round_trip_and_verify_only_the_right_password() {
        let dir = std::env::temp_dir().join(format!("vigie-users-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(Users::load(&dir).unwrap(), Users::default());
        let mut u = Users::default();
        u.set("marie", Role::Maintenance, "correct horse").unwrap();
        assert!(matches!(
            u.set("two words", Role::Operator, "long enough"),
            Err(UsersError::Invalid(_))
        ));
        assert!(matches!(
            u.set("paul", Role::Operator, "short"),
            Err(UsersError::Invalid(_))
        ));
        u.save(&dir).unwrap();
        let text = std::fs::read_to_string(Users::path(&dir)).unwrap();
        assert!(text.contains("$argon2id$") && !text.contains("correct horse"));
        let back = Users::load(&dir).unwrap();
        assert_eq!(back, u);
        assert_eq!(
            back.verify("marie", "correct horse").unwrap(),
            Role::Maintenance
        );
        assert!(matches!(
            back.verify("marie", "wrong"),
            Err(UsersError::Refused)
        ));
        assert!(matches!(
            back.verify("nobody", "correct horse"),
            Err(UsersError::Refused)
        ));
        // A damaged file is an error with its line and column, never a silent skip.
        std::fs::write(Users::path(&dir), "[(name: \"x\", role: boss, hash: \"\")]").unwrap();
        let e = Users::load(&dir).unwrap_err().to_string();
        assert!(e.contains("users.ron:1:"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
