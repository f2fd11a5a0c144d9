"""Controllers: the Controller interface (base.py), the PID of paper 001 eq. 9, Stanley, and
the registry that builds one by name."""
