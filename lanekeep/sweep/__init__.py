"""Grids of episodes over scenario parameters (local processes or Ray), their store and plots."""
