"""Independent reference implementations and the scripts that produce stored references."""
