//! The memory budget: the most host memory a scene may make cadr allocate. A small file can
//! describe a huge scene (shared subgraphs multiply paths: three levels of a thousand children
//! are a billion parts), and an allocation the system cannot satisfy aborts the process, taking
//! the host application and its users' unsaved work with it. Scenes are therefore checked
//! against the budget before anything of their size is allocated, and refused with an error
//! that says how much they would need.
//!
//! The budget is the machine's physical memory, or `CADR_MEMORY_BUDGET` (bytes, or with a
//! `K`, `M`, `G` or `T` suffix, binary).

/// The variable that sets the budget.
pub const VARIABLE: &str = "CADR_MEMORY_BUDGET";

/// Host bytes a drawn part (one part of one instance) costs once it is flattened, in the scene
/// tree and in the GPU scene: about 200 measured at 10 000 000 parts, rounded up for the
/// transient copies made while building.
pub const HOST_BYTES_PER_DRAWN_PART: u64 = 256;

/// The budget in bytes: `CADR_MEMORY_BUDGET`, else the physical memory, else unlimited.
pub fn budget() -> Result<u64, String> {
    match std::env::var(VARIABLE) {
        Ok(text) => parse_size(&text).ok_or_else(|| {
            format!("{VARIABLE}={text} is not a size (bytes, or a number with K, M, G or T)")
        }),
        Err(_) => Ok(physical_memory().unwrap_or(u64::MAX)),
    }
}

/// Parses `123`, `64M`, `8G`, `1T` (binary multiples; an optional `B` or `iB` after the suffix).
pub fn parse_size(text: &str) -> Option<u64> {
    let text = text.trim();
    let text = text
        .strip_suffix("iB")
        .or_else(|| text.strip_suffix('B'))
        .unwrap_or(text);
    let (number, shift) = match text.chars().last()?.to_ascii_uppercase() {
        'K' => (&text[..text.len() - 1], 10),
        'M' => (&text[..text.len() - 1], 20),
        'G' => (&text[..text.len() - 1], 30),
        'T' => (&text[..text.len() - 1], 40),
        _ => (text, 0),
    };
    number.trim().parse::<u64>().ok()?.checked_mul(1 << shift)
}

/// Total physical memory (Linux: `MemTotal` of `/proc/meminfo`).
pub fn physical_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// Checks that a scene of `parts` drawn parts fits the budget.
pub fn check_drawn_parts(parts: u64) -> Result<(), String> {
    let budget = budget()?;
    let needed = parts.saturating_mul(HOST_BYTES_PER_DRAWN_PART);
    if needed > budget {
        return Err(over_budget(
            &format!("the scene expands to {parts} drawn parts, which"),
            needed,
            budget,
        ));
    }
    Ok(())
}

/// The refusal of `what`, which would take `needed` bytes of host memory, over `budget`.
pub fn over_budget(what: &str, needed: u64, budget: u64) -> String {
    format!(
        "{what} would take about {} of host memory, more than the memory budget of {} ({VARIABLE} changes it)",
        human_bytes(needed),
        human_bytes(budget)
    )
}

/// `bytes` in the largest binary unit it reaches, to one decimal.
fn human_bytes(bytes: u64) -> String {
    let units = [(30, "GiB"), (20, "MiB"), (10, "KiB")];
    match units.iter().find(|&&(shift, _)| bytes >> shift > 0) {
        Some(&(shift, unit)) => format!("{:.1} {unit}", bytes as f64 / (1u64 << shift) as f64),
        None => format!("{bytes} bytes"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_suffixes() {
        assert_eq!(parse_size("123"), Some(123));
        assert_eq!(parse_size("64M"), Some(64 << 20));
        assert_eq!(parse_size("8 GiB"), Some(8 << 30));
        assert_eq!(parse_size("1t"), Some(1 << 40));
        assert_eq!(parse_size("lots"), None);
        assert_eq!(parse_size("99999999999T"), None);
    }

    #[test]
    fn sizes_read_in_their_largest_unit() {
        assert_eq!(human_bytes(512), "512 bytes");
        assert_eq!(human_bytes(4 << 10), "4.0 KiB");
        assert_eq!(human_bytes(3 << 19), "1.5 MiB");
        assert_eq!(human_bytes(1 << 30), "1.0 GiB");
    }

    #[test]
    fn the_machine_has_a_physical_memory() {
        assert!(physical_memory().is_some_and(|bytes| bytes > 1 << 20));
    }
}
