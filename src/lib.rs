//! The command line (SPEC §7, [`cli`]) of both programs: `clayloft`, which holds no window code
//! and hands the commands that open a window to `clayloft-editor` next to it (`src/main.rs`),
//! and `clayloft-editor`, the application (SPEC §8) with the same commands (`src/editor.rs`).
//! Nothing here links the app's libraries.

pub mod cli;
mod flow;
mod printer;

use cli::Failure;
