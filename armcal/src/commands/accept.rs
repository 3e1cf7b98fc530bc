//! The `--accept-…` flags: each accepts deliberately one kind of input that
//! `armcal::plausible` refuses as a likely mistake. One scheme for every command.

/// Flags that accept inputs refused as implausible.
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub struct AcceptArgs {
    /// Accept joint readings beyond a turn and point or length data whose size is not the
    /// arm's (refused as degrees, metres or inches).
    #[arg(long)]
    accept_units: bool,
    /// Accept temperatures outside 0..45 °C (refused as °F or a sensor fault).
    #[arg(long)]
    accept_temperature: bool,
    /// Accept rows that repeat an earlier row's joint readings exactly (refused as a row
    /// pasted twice).
    #[arg(long)]
    accept_duplicates: bool,
    /// Accept joint columns that a swap (or reversal) of two columns fits far better than
    /// their order as given (refused as columns out of order).
    #[arg(long)]
    accept_order: bool,
}

impl AcceptArgs {
    /// What the flags accept.
    pub fn accept(self) -> armcal::plausible::Accept {
        armcal::plausible::Accept {
            units: self.accept_units,
            temperature: self.accept_temperature,
            duplicates: self.accept_duplicates,
            order: self.accept_order,
            ..Default::default()
        }
    }
}
