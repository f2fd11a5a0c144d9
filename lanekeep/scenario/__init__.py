"""Scenario files: the schema (frozen dataclasses read strictly from TOML), the shipped scenarios
(shipped/) and the generated format reference."""
