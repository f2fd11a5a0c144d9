"""The lowest layer: strict config reading, plug-in loading, stop signals, stage timing, progress
bars
and the vehicle-signal types every layer above shares. Imports nothing else of lanekeep."""
