"""Faces for learning agents: dm_env and Gymnasium environments over one Episode."""
