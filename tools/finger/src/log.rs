//! `finger log`: the firmware's defmt log, decoded with the image's `.defmt` table.
//! In QEMU the frames come by semihosting into a file (scripts/run and `finger --qemu` write
//! one); on a real board by RTT, which probe-rs reads. Not here: the console.
use std::io::{Read, Write};
use std::path::Path;
use std::time::Duration;

/// Decode the defmt frames in `bytes` with the table of the ELF `elf`; one text line each.
pub fn decode(elf: &[u8], bytes: &[u8]) -> Result<Vec<String>, String> {
    let table = defmt_decoder::Table::parse(elf)
        .map_err(|e| format!("the image's defmt table: {e}"))?
        .ok_or("the image has no .defmt section (built without the `log` feature?)")?;
    let mut dec = table.new_stream_decoder();
    dec.received(bytes);
    let mut lines = Vec::new();
    loop {
        match dec.decode() {
            Ok(frame) => lines.push(frame.display(false).to_string()),
            Err(defmt_decoder::DecodeError::UnexpectedEof) => break,
            Err(defmt_decoder::DecodeError::Malformed) => return Err("malformed defmt frame (is this log from this image?)".into()),
        }
    }
    Ok(lines)
}

/// Decode `log` as it grows, printing each frame; with `follow` false, stop at its end.
pub fn follow(elf: &Path, log: &Path, follow: bool, out: &mut impl Write) -> Result<(), String> {
    let elf_bytes = std::fs::read(elf).map_err(|e| format!("{}: {e}", elf.display()))?;
    let table = defmt_decoder::Table::parse(&elf_bytes)
        .map_err(|e| format!("the image's defmt table: {e}"))?
        .ok_or("the image has no .defmt section (built without the `log` feature?)")?;
    let mut dec = table.new_stream_decoder();
    let mut f = std::fs::File::open(log).map_err(|e| format!("{}: {e}", log.display()))?;
    let mut buf = [0u8; 4096];
    loop {
        let n = f.read(&mut buf).map_err(|e| format!("{}: {e}", log.display()))?;
        if n == 0 {
            if !follow {
                return Ok(());
            }
            std::thread::sleep(Duration::from_millis(100));
            continue;
        }
        dec.received(&buf[..n]);
        loop {
            match dec.decode() {
                Ok(frame) => {
                    let _ = writeln!(out, "{}", frame.display(false));
                }
                Err(defmt_decoder::DecodeError::UnexpectedEof) => break,
                Err(defmt_decoder::DecodeError::Malformed) => return Err("malformed defmt frame (is this log from this image?)".into()),
            }
        }
        let _ = out.flush();
    }
}
