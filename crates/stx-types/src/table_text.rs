//! The data lines of a hand-edited text table (a forecast, a flight log), each with its line
//! number as an editor shows it: blank lines and `#` comments (indented ones too) left out.
//! The CSV readers hand the data lines to the `csv` crate and map its line numbers back, since
//! its own count leaves out the comment lines it skips.

/// The data lines joined by `\n`, and the 1-based number of each in the original text.
pub fn data_lines(text: &str) -> (String, Vec<usize>) {
    let kept: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| {
            let l = l.trim();
            !l.is_empty() && !l.starts_with('#')
        })
        .map(|(i, l)| (i + 1, l))
        .collect();
    let table = kept.iter().map(|(_, l)| *l).collect::<Vec<_>>().join("\n");
    (table, kept.into_iter().map(|(n, _)| n).collect())
}

/// The original line number of data line `line` (1-based, as the `csv` crate counts), or 0
/// when there is none.
pub fn original_line(numbers: &[usize], line: u64) -> usize {
    (line as usize)
        .checked_sub(1)
        .and_then(|i| numbers.get(i))
        .copied()
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comments_and_blank_lines_keep_the_editor_s_numbers() {
        let (table, numbers) = data_lines("# head\n\n  # indented\na,b\r\n\nc,d\n");
        assert_eq!(table, "a,b\nc,d");
        assert_eq!(numbers, [4, 6]);
        assert_eq!(original_line(&numbers, 2), 6);
        assert_eq!(original_line(&numbers, 0), 0);
        assert_eq!(original_line(&numbers, 3), 0);
    }
}
