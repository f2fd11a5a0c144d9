"""Controllers: the Controller interface, the PID of paper 001 eq. 9, Stanley, and the registry
that builds one by name."""
