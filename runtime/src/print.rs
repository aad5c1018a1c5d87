//! Printing from kernels: the `println!` sites a kernel has, the buffer a dispatch writes
//! them to, and how that buffer turns back into text after the dispatch.
//!
//! A kernel that prints has one more binding, [`PRINT_BINDING`]: an array of `u32` words.
//! Word 0 counts the words reserved so far, word 1 the prints that did not fit; from
//! word 2 on, each print is a record: its site's index, then the site's argument words.
//! An invocation reserves its record with one atomic add, so records never interleave;
//! their order is the order the reservations happened in. The batch that records the
//! dispatch binds a zeroed buffer, reads it back with its other results and prints the
//! records when the submission is waited for. The CPU backend runs the kernel's own
//! Rust function, whose `println!` prints directly; its buffer stays empty.

pub use cohort_compiler::abi::{PrintFormat, PrintSite, PrintStream, HEADER_WORDS, PRINT_BINDING};

/// The size of the buffer, unless `COHORT_PRINT_BUFFER_BYTES` says otherwise.
pub const DEFAULT_BUFFER_BYTES: usize = 4 << 20;

/// Words of the print buffer a dispatch gets: `COHORT_PRINT_BUFFER_BYTES` (at least
/// enough for the header and one word), else [`DEFAULT_BUFFER_BYTES`].
pub(crate) fn buffer_words() -> usize {
    let bytes = std::env::var("COHORT_PRINT_BUFFER_BYTES")
        .ok()
        .and_then(|s| s.trim().parse::<usize>().ok())
        .unwrap_or(DEFAULT_BUFFER_BYTES);
    (bytes / 4).max(HEADER_WORDS + 1)
}

/// What one dispatch printed, decoded from its buffer.
#[derive(Debug, Default, PartialEq, Eq)]
pub struct Printed {
    /// The texts in record order, each with its stream.
    pub texts: Vec<(PrintStream, String)>,
    /// Prints that did not fit in the buffer.
    pub dropped: u32,
}

/// Decodes a print buffer written by a kernel with `sites`.
pub fn decode(sites: &[PrintSite], words: &[u32]) -> Printed {
    let mut out = Printed::default();
    if words.len() < HEADER_WORDS {
        return out;
    }
    let data = &words[HEADER_WORDS..];
    let used = (words[0] as usize).min(data.len());
    out.dropped = words[1];
    let mut at = 0;
    while at < used {
        // A record is written whole or not at all, and reservations are contiguous, so
        // every word below the cursor that fits belongs to a complete record.
        let Some(site) = sites.get(data[at] as usize) else {
            break;
        };
        let end = at + 1 + site.words as usize;
        if end > used {
            break;
        }
        out.texts
            .push((site.stream, (site.format)(&data[at + 1..end])));
        at = end;
    }
    out
}

/// Writes what a dispatch of `kernel` printed to the process's stdout and stderr.
pub(crate) fn emit(kernel: &str, printed: &Printed) {
    use std::io::Write;
    let (mut stdout, mut stderr) = (std::io::stdout().lock(), std::io::stderr().lock());
    for (stream, text) in &printed.texts {
        // Printing is best effort, as Rust's `print!` is not (it panics on a closed
        // stdout); a kernel's debug output must not turn a finished dispatch into an error.
        let _ = match stream {
            PrintStream::Stdout => stdout.write_all(text.as_bytes()),
            PrintStream::Stderr => stderr.write_all(text.as_bytes()),
        };
    }
    let _ = stdout.flush();
    if printed.dropped > 0 {
        let _ = writeln!(
            stderr,
            "cohort: kernel `{kernel}`: {} prints were dropped because the print buffer \
             ({} bytes) is full; set COHORT_PRINT_BUFFER_BYTES to a larger size",
            printed.dropped,
            buffer_words() * 4
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    fn site(words: u32) -> PrintSite {
        PrintSite {
            words,
            stream: PrintStream::Stdout,
            format: Arc::new(|w: &[u32]| format!("{w:?}")),
            location: "here".into(),
        }
    }

    #[test]
    fn decodes_whole_records_below_the_cursor_only() {
        let sites = [site(1), site(2)];
        // 7 data words, cursor 9: the third record (site 1, 3 words) does not fit;
        // 4 dropped.
        let buf = [9, 4, 1, 10, 11, 0, 12, 1, 13];
        let p = decode(&sites, &buf);
        assert_eq!(p.dropped, 4);
        let texts: Vec<&str> = p.texts.iter().map(|(_, t)| t.as_str()).collect();
        assert_eq!(texts, ["[10, 11]", "[12]"]);
        // An empty buffer and an unknown site decode to nothing more.
        assert_eq!(decode(&sites, &[0, 0]), Printed::default());
        assert_eq!(decode(&sites, &[2, 0, 7, 1]).texts.len(), 0);
    }
}
