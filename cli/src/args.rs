//! A small command-line parser: `cadr COMMAND [ARGS] [--flag value]`.

/// Parsed arguments: positionals in order, flags by name.
#[derive(Debug, Default)]
pub struct Args {
    positionals: Vec<String>,
    options: Vec<(String, Option<String>)>,
}

/// Flags that take no value.
const SWITCHES: &[&str] = &[
    "--validation",
    "--no-validation",
    "--help",
    "-h",
    "--quiet",
    "--baseline",
    "--all",
    "--sweep",
    "--no-replay",
];

impl Args {
    /// Splits `args` (without the program and command names) of `command`.
    pub fn parse(command: &str, args: impl IntoIterator<Item = String>) -> Result<Self, String> {
        // `cadr techniques --json` and `cadr pick --json` print JSON; elsewhere `--json FILE`
        // names a file.
        let command_switches: &[&str] = if command == "techniques" || command == "pick" {
            &["--json"]
        } else {
            &[]
        };
        let mut parsed = Self::default();
        let mut iter = args.into_iter();
        while let Some(arg) = iter.next() {
            if let Some((name, value)) = arg.split_once('=').filter(|(n, _)| n.starts_with("--")) {
                parsed
                    .options
                    .push((name.to_owned(), Some(value.to_owned())));
            } else if SWITCHES.contains(&arg.as_str()) || command_switches.contains(&arg.as_str()) {
                parsed.options.push((arg, None));
            } else if arg.starts_with('-') && arg.len() > 1 {
                let value = iter.next().ok_or_else(|| format!("{arg} needs a value"))?;
                parsed.options.push((arg, Some(value)));
            } else {
                parsed.positionals.push(arg);
            }
        }
        Ok(parsed)
    }

    /// The value of the last occurrence of any of `names`.
    pub fn value(&self, names: &[&str]) -> Option<&str> {
        self.options
            .iter()
            .rev()
            .find(|(n, _)| names.contains(&n.as_str()))
            .and_then(|(_, v)| v.as_deref())
    }

    /// Whether the switch `name` was given.
    pub fn flag(&self, name: &str) -> bool {
        self.options.iter().any(|(n, _)| n == name)
    }

    /// Positional arguments.
    pub fn positionals(&self) -> &[String] {
        &self.positionals
    }

    /// Fails on any option not in `known`.
    pub fn reject_unknown(&self, command: &str, known: &[&str]) -> Result<(), String> {
        match self
            .options
            .iter()
            .find(|(n, _)| !known.contains(&n.as_str()))
        {
            Some((name, _)) => Err(format!(
                "cadr {command}: unknown option {name} (see cadr --help)"
            )),
            None => Ok(()),
        }
    }
}

/// Parses `WIDTHxHEIGHT`.
pub fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let bad = || format!("--size {text}: expected WIDTHxHEIGHT, e.g. 1024x768");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h) = (
        w.trim().parse::<u32>().map_err(|_| bad())?,
        h.trim().parse::<u32>().map_err(|_| bad())?,
    );
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!("--size {text}: each side must be 1 to 16384"));
    }
    Ok((w, h))
}
