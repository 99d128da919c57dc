//! `clayloft`: the command line (SPEC §7, [`cli`]) without the application's window code, so
//! that a batch command (`clayloft gcode`) starts as a small program: the application's
//! libraries register hundreds of types before `main` in every process that links them
//! (0.8 ms), and its 145 MB of code fault in more pages. The commands that open a window
//! (`clayloft [DESIGN]`, `clayloft screenshot`) are handed, with their arguments, to
//! `clayloft-editor` next to this program (built with it), which runs them in the same process.

use std::process::ExitCode;

use clayloft::cli::{self, Failure, Window};

fn main() -> ExitCode {
    cli::main(hand_to_editor)
}

/// Runs `clayloft-editor` next to this program with this program's arguments, in this process
/// where the system allows (Unix: same process id, so a script that started `clayloft` can
/// still stop it), else as a child whose exit code is passed on.
fn hand_to_editor(_: Window) -> Result<ExitCode, Failure> {
    let me = std::env::current_exe()
        .map_err(|e| Failure(format!("cannot find this program's own file: {e}")))?;
    let editor = me.with_file_name(format!("clayloft-editor{}", std::env::consts::EXE_SUFFIX));
    let mut command = std::process::Command::new(&editor);
    command.args(std::env::args_os().skip(1));
    let not_started = |e: std::io::Error| {
        Failure(format!(
            "{}: cannot start the editor: {e} (it is built with this program: cargo build --release)",
            editor.display()
        ))
    };
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        // Returns only when the editor could not be started.
        Err(not_started(command.exec()))
    }
    #[cfg(not(unix))]
    {
        let status = command.status().map_err(not_started)?;
        Ok(ExitCode::from(
            status.code().map_or(2, |c| u8::try_from(c).unwrap_or(2)),
        ))
    }
}
