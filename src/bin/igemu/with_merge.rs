//! A command with a `merge` subcommand (`igemu sweep merge`, `igemu sequence merge`): either
//! the command's own arguments or the subcommand's. The clap traits are written out: the
//! derive cannot make a command's own arguments optional next to a subcommand (an optional
//! flattened struct with a flattened member is never found in the matches, clap 4.6). The
//! merge arguments' `#[command(about = ...)]` is the subcommand's help line.

use clap::{ArgMatches, Args, Command, FromArgMatches};

/// `igemu CMD ...` (`Run`) or `igemu CMD merge ...` (`Merge`).
pub enum WithMerge<R, M> {
    /// The command itself.
    Run(R),
    /// Its `merge` subcommand.
    Merge(M),
}

impl<R: FromArgMatches, M: FromArgMatches> FromArgMatches for WithMerge<R, M> {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        Self::from_arg_matches_mut(&mut m.clone())
    }

    fn from_arg_matches_mut(m: &mut ArgMatches) -> Result<Self, clap::Error> {
        match m.remove_subcommand() {
            Some((name, mut sub)) if name == "merge" => {
                M::from_arg_matches_mut(&mut sub).map(WithMerge::Merge)
            }
            _ => R::from_arg_matches_mut(m).map(WithMerge::Run),
        }
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl<R: Args, M: Args> Args for WithMerge<R, M> {
    fn augment_args(c: Command) -> Command {
        R::augment_args(c)
            .subcommand(M::augment_args(Command::new("merge")))
            .args_conflicts_with_subcommands(true)
            .subcommand_negates_reqs(true)
    }

    fn augment_args_for_update(c: Command) -> Command {
        R::augment_args_for_update(c)
            .subcommand(M::augment_args_for_update(Command::new("merge")))
            .args_conflicts_with_subcommands(true)
            .subcommand_negates_reqs(true)
    }
}
