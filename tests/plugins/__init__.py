"""Example plug-in modules the tests load (not shipped)."""
