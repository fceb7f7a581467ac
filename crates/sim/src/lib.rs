//! Simulated temperature-chamber runs (filled by the simulator issue).
