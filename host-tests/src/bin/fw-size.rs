//! fw-size: flash and static RAM of a firmware ELF (default: the release image).
//! Flash = every allocated section loaded from flash (vector table, .text, .rodata, .data's
//! initial values); static RAM = .data + .bss + .uninit (the stack is not counted).
//! Usage: cargo run --bin fw-size [-- path/to/elf]   (from host-tests/)
use object::{Object, ObjectSection, SectionFlags};

fn main() {
    let path = std::env::args().nth(1).unwrap_or_else(|| {
        let t = std::env::var("CARGO_TARGET_DIR").unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../target").into());
        format!("{t}/thumbv7em-none-eabihf/release/finger-fw")
    });
    let data = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e} (build it: cargo build --release at the top)"));
    let elf = object::File::parse(&*data).expect("ELF");
    let (mut flash, mut ram) = (0u64, 0u64);
    for s in elf.sections() {
        let alloc = matches!(s.flags(), SectionFlags::Elf { sh_flags } if sh_flags & 0x2 != 0);
        if !alloc || s.size() == 0 {
            continue;
        }
        let name = s.name().unwrap_or("");
        let addr = s.address();
        let in_ram = (0x2000_0000..0x2002_0000).contains(&addr);
        if in_ram {
            ram += s.size();
            if name == ".data" {
                flash += s.size();
            }
        } else if (0x0800_0000..0x0810_0000).contains(&addr) {
            flash += s.size();
        }
    }
    println!("{path}");
    println!("flash={flash} bytes ({:.1} KiB, target <= 64 KiB)", flash as f64 / 1024.0);
    println!("ram={ram} bytes static ({:.1} KiB, target <= 16 KiB)", ram as f64 / 1024.0);
}
