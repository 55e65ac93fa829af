//! A command's summary as text: what a writer writes, collected for the CLI to print.

/// What `write` writes, as text.
pub fn summary(
    write: impl FnOnce(&mut dyn std::io::Write) -> anyhow::Result<()>,
) -> anyhow::Result<String> {
    let mut text = Vec::new();
    write(&mut text)?;
    Ok(String::from_utf8(text)?)
}

/// A command's text and how it ended. The text is printed either way (a sweep's table when
/// some runs failed, a run's files when it was interrupted); then `end`'s error, if any, is
/// reported and sets the exit code.
pub struct Ended {
    pub text: String,
    pub end: anyhow::Result<()>,
}
