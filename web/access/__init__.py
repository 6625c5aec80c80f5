"""Who may do what: the users file, the role table, logins and the audit trail."""
