//! Who may do what at the console (issue 19): four roles and the permissions that need
//! more than an operator. The accounts and their password hashes live at the binary
//! edge (`app/src/console/users.rs`); the core only answers "may this role do that".

use serde::{Deserialize, Serialize};

/// A console role.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// Runs production: Start, Stop, Reset, alarms, manual mode through the filter.
    #[default]
    Operator,
    /// Finds and fixes errors: edits the program, changes the filter mode, bypasses a
    /// constraint for a limited time.
    Maintenance,
    /// Runs training on the emulator: loads exercises, injects faults, turns the filter
    /// off to show what it prevents.
    Trainer,
    /// Everything, and the user accounts.
    Administrator,
}

/// An action that needs more than the operator role.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Permission {
    /// Open maintenance mode on a program that drives the plant and edit it.
    EditProgram,
    /// Change the filter's mode (enforce, report only, off).
    ChangeFilterMode,
    /// Bypass one safety constraint for a limited time.
    BypassConstraint,
    /// Load training exercises and inject faults.
    Train,
}

impl Role {
    /// Every role, in order.
    pub const ALL: [Role; 4] = [
        Role::Operator,
        Role::Maintenance,
        Role::Trainer,
        Role::Administrator,
    ];

    /// True when this role may do `p`.
    pub fn may(self, p: Permission) -> bool {
        match self {
            Role::Administrator => true,
            Role::Maintenance => matches!(
                p,
                Permission::EditProgram
                    | Permission::ChangeFilterMode
                    | Permission::BypassConstraint
            ),
            Role::Trainer => matches!(p, Permission::Train | Permission::ChangeFilterMode),
            Role::Operator => false,
        }
    }

    /// Its name (`maintenance`), as in the accounts file and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Role::Operator => "operator",
            Role::Maintenance => "maintenance",
            Role::Trainer => "trainer",
            Role::Administrator => "administrator",
        }
    }

    /// Parses a role name.
    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|r| r.name() == s.trim())
    }
}

impl Permission {
    /// What it is, for a refusal ("editing the program needs …").
    pub fn what(self) -> &'static str {
        match self {
            Permission::EditProgram => "editing the program",
            Permission::ChangeFilterMode => "changing the filter's mode",
            Permission::BypassConstraint => "bypassing a safety constraint",
            Permission::Train => "loading exercises and injecting faults",
        }
    }

    /// The roles that may, for a refusal.
    pub fn roles(self) -> Vec<&'static str> {
        Role::ALL
            .into_iter()
            .filter(|r| r.may(self))
            .map(Role::name)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The whole table, exhaustively: an operator may nothing of these; the program,
    /// the filter's mode and a bypass need maintenance (or administrator); training
    /// needs a trainer (or administrator).
    #[test]
    fn the_permission_table() {
        use Permission::*;
        let table = [
            (Role::Operator, [false, false, false, false]),
            (Role::Maintenance, [true, true, true, false]),
            (Role::Trainer, [false, true, false, true]),
            (Role::Administrator, [true, true, true, true]),
        ];
        for (role, expected) in table {
            let got = [EditProgram, ChangeFilterMode, BypassConstraint, Train].map(|p| role.may(p));
            assert_eq!(got, expected, "{role:?}");
            assert_eq!(Role::parse(role.name()), Some(role));
        }
        assert_eq!(Role::parse("root"), None);
        assert_eq!(BypassConstraint.roles(), ["maintenance", "administrator"]);
    }
}
