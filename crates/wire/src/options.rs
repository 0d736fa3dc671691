//! What the socket loops of the link ([`crate::replay::send_recording`],
//! [`crate::receiver::receive`]) refuse: options out of range, named as the `jawtrack` flags
//! spell them, and socket failures, named by what was being done.

/// An option whose value cannot be, e.g. `--loss must be a probability in [0, 1), got 2`.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("--{option} must be {wanted}, got {value}")]
pub struct BadOption {
    /// The option, spelt as its `jawtrack` flag without the dashes (`loss`, `max-clock-skew`).
    pub option: &'static str,
    /// What its value must be, in words.
    pub wanted: &'static str,
    /// The value given.
    pub value: f64,
}

/// Why a send or receive loop stopped short.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// An option out of range (checked before the socket is touched).
    #[error(transparent)]
    Option(#[from] BadOption),
    /// A replay of no frames at all.
    #[error("no frames to replay")]
    NoFrames,
    /// The socket failed while `doing` something (`opening a UDP socket`, `sending`,
    /// `receiving`).
    #[error("{doing}")]
    Io {
        /// What was being done.
        doing: &'static str,
        /// The socket's error.
        #[source]
        source: std::io::Error,
    },
    /// The socket could not be set up (non-blocking mode, read timeout).
    #[error(transparent)]
    Socket(#[from] std::io::Error),
}

impl LinkError {
    /// A socket error met while `doing` something.
    pub(crate) fn io(doing: &'static str) -> impl FnOnce(std::io::Error) -> LinkError {
        move |source| LinkError::Io { doing, source }
    }
}

/// `value` if it is a probability a draw can use: in [0, 1).
pub(crate) fn probability(option: &'static str, value: f64) -> Result<f64, BadOption> {
    if (0.0..1.0).contains(&value) {
        Ok(value)
    } else {
        Err(BadOption { option, wanted: "a probability in [0, 1)", value })
    }
}

/// `value` if it is finite and above zero (or, with `zero_too`, zero), else `wanted`.
pub(crate) fn positive(
    option: &'static str,
    value: f64,
    zero_too: bool,
    wanted: &'static str,
) -> Result<f64, BadOption> {
    if value.is_finite() && (value > 0.0 || zero_too && value == 0.0) {
        Ok(value)
    } else {
        Err(BadOption { option, wanted, value })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bad_option_names_its_flag_and_value() {
        let e = probability("loss", 2.0).expect_err("2 is no probability");
        assert_eq!(e.to_string(), "--loss must be a probability in [0, 1), got 2");
        assert_eq!(probability("loss", 0.0), Ok(0.0));
        assert!(probability("loss", f64::NAN).is_err() && probability("loss", 1.0).is_err());
        assert!(positive("rate", 0.0, false, "positive").is_err());
        assert_eq!(positive("max-clock-skew", 0.0, true, "≥ 0"), Ok(0.0));
        assert!(positive("duration", f64::INFINITY, false, "positive").is_err());
        let io = LinkError::io("sending")(std::io::Error::other("down"));
        assert_eq!(
            (io.to_string(), std::error::Error::source(&io).map(|s| s.to_string())),
            ("sending".into(), Some("down".into()))
        );
    }
}
