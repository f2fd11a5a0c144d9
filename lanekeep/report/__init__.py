"""What a run writes: the rerun recording, PNG plots, JSON, JUnit XML and terminal tables, with one
palette."""
