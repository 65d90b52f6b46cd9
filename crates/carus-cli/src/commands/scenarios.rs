//! `carus scenarios` lists the built-in scenarios with one-line
//! descriptions; `carus scenarios show NAME` prints one as a complete TOML
//! file that `carus run FILE` takes back.

use carus_labour::{Scenario, BUILTINS};
use serde_json::json;

use super::{print_json, Status};

#[derive(clap::Args)]
pub struct ScenariosArgs {
    #[command(subcommand)]
    pub command: Option<ScenariosCommand>,
    /// Print one JSON object on standard output and nothing else there.
    #[arg(long, global = true)]
    pub json: bool,
}

#[derive(clap::Subcommand)]
pub enum ScenariosCommand {
    /// Print a built-in scenario as a complete, runnable TOML file.
    Show {
        /// Name of the built-in scenario (`carus scenarios` lists them).
        name: String,
    },
}

pub fn run(args: &ScenariosArgs) -> anyhow::Result<Status> {
    match &args.command {
        None => {
            let mut list = Vec::new();
            for (name, _) in BUILTINS {
                let s = Scenario::builtin(name)?;
                list.push((name, s.description));
            }
            if args.json {
                let items: Vec<_> = list
                    .iter()
                    .map(|(n, d)| json!({ "name": n, "description": d }))
                    .collect();
                print_json(&json!({ "scenarios": items }))?;
            } else {
                let width = list.iter().map(|(n, _)| n.len()).max().unwrap_or(0);
                for (name, description) in &list {
                    println!("{name:width$}  {description}");
                }
            }
        }
        Some(ScenariosCommand::Show { name }) => {
            // `show` takes only a built-in's name: another is a bad argument.
            let s = Scenario::builtin(name).map_err(|e| super::BadArgument(e.to_string()))?;
            let text = s.to_toml()?;
            if args.json {
                print_json(&json!({ "name": name, "toml": text }))?;
            } else {
                print!("{text}");
            }
        }
    }
    Ok(Status::Success)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `show` takes a built-in's name; another is a bad argument (exit 2).
    #[test]
    fn an_unknown_name_is_a_bad_argument() {
        let args = ScenariosArgs { command: Some(ScenariosCommand::Show { name: "nope".into() }), json: true };
        let e = run(&args).expect_err("refused");
        assert!(e.downcast_ref::<crate::commands::BadArgument>().is_some() && e.to_string().contains("`nope`"), "{e}");
    }
}
