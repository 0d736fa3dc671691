//! The desktop end of the phone link: `jawtrack receive` ([`receive`]) records the sealed pose
//! datagrams the phone streams, `jawtrack send` ([`send`]) is a phone simulator, and
//! `jawtrack keygen` makes a pairing key. The datagram itself lives in `jawtrack_wire`.

pub(crate) mod receive;
pub(crate) mod send;

use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_wire::{Key, Security};

/// How the pairing key is given, shared by `receive` and `send`.
#[derive(Args)]
pub(crate) struct KeyArgs {
    /// The pairing key, 64 hex digits (from `jawtrack keygen`); or set JAWTRACK_KEY, which
    /// keeps it out of the process list.
    #[arg(long, env = "JAWTRACK_KEY", hide_env_values = true)]
    key: Option<String>,
    /// Send and accept unauthenticated, unencrypted datagrams. For development only: never with
    /// patient data.
    #[arg(long, conflicts_with = "key")]
    insecure_plaintext: bool,
}

impl KeyArgs {
    pub(super) fn security(&self) -> Result<Security> {
        match (&self.key, self.insecure_plaintext) {
            (Some(k), false) => Ok(Security::Sealed(k.parse().context("--key")?)),
            (None, true) => Ok(Security::Plaintext),
            _ => bail!(
                "give the pairing key with --key (or JAWTRACK_KEY); `jawtrack keygen` makes one. \
                 --insecure-plaintext is for development only"
            ),
        }
    }
}

/// Prints a new pairing key and its id.
pub(crate) fn keygen() {
    let key = Key::generate();
    tell!("key id {} (safe to share; the key itself is secret: give it to the phone and the receiver only)", key.id());
    say!("{}", key.to_hex());
}
