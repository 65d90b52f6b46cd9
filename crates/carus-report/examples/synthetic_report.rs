//! Writes the report of a synthetic history (docs/examples/report-textbook-synthetic.html):
//!
//! `cargo run --release -p carus-report --example synthetic_report -- textbook OUT.html`
//! (`textbook` or `straight-push`).

use std::path::PathBuf;
use std::process::ExitCode;

use carus_report::demo::Demo;
use carus_report::write_report_file;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(which), Some(out)) = (args.first(), args.get(1)) else {
        eprintln!("usage: synthetic_report textbook|straight-push OUT.html");
        return ExitCode::from(2);
    };
    let demo = match which.as_str() {
        "textbook" => Demo::textbook(),
        "straight-push" => Demo::straight_push(),
        other => {
            eprintln!("unknown history `{other}`: give textbook or straight-push");
            return ExitCode::from(2);
        }
    };
    let title = format!("{which} (synthetic)");
    match demo.and_then(|d| write_report_file(&d.input(&title), &PathBuf::from(out))) {
        Ok(warnings) => {
            for w in warnings {
                eprintln!("warning: {w}");
            }
            eprintln!("wrote {out}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}
