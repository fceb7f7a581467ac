//! Command-line arguments that several commands share: the run a command reads ([`run`], flattened
//! into `fit`, `eval`, `diagnose`, `compare` and `report`) and the value parsers of the numeric
//! flags ([`check`]).
//!
//! Why a module of its own below `cmd/`: `cmd/` holds one module per subcommand and nothing else;
//! these pieces belong to no one command, and the Python binding (`python/`) builds a [`run::RunArgs`]
//! without going through any command.

pub mod check;
pub mod run;
