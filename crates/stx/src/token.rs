//! `stx token new`: a strong random token for the station's `[[tokens]]`, printed as the
//! TOML entry to paste into the station config.

use std::io::Write;

use anyhow::Context;
use clap::{Args, Subcommand, ValueEnum};

#[derive(Args, Debug)]
pub struct TokenArgs {
    #[command(subcommand)]
    command: TokenCommand,
}

#[derive(Subcommand, Debug)]
enum TokenCommand {
    /// Print a new `[[tokens]]` entry: 256 random bits from the operating system, hex.
    New {
        /// The holder's name, as the station shows and records it.
        #[arg(long, default_value = "operator")]
        name: String,
        /// What the holder may do.
        #[arg(long, value_enum, default_value = "operator")]
        role: TokenRole,
    },
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum TokenRole {
    /// Commands the drone.
    Operator,
    /// Watches only.
    Viewer,
}

pub fn run(args: TokenArgs) -> anyhow::Result<()> {
    match args.command {
        TokenCommand::New { name, role } => {
            let mut bytes = [0_u8; 32];
            getrandom::fill(&mut bytes)
                .map_err(|e| anyhow::anyhow!("{e}"))
                .context("the operating system's random numbers")?;
            let token: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
            let role = match role {
                TokenRole::Operator => "operator",
                TokenRole::Viewer => "viewer",
            };
            let name = name.replace('\\', "\\\\").replace('"', "\\\"");
            writeln!(
                std::io::stdout(),
                "[[tokens]]\nname = \"{name}\"\ntoken = \"{token}\"\nrole = \"{role}\""
            )
            .context("stdout")?;
            Ok(())
        }
    }
}
