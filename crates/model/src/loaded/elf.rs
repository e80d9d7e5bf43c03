//! A model library's file checked against its own ELF headers before the dynamic loader maps
//! it. The loader maps each loadable segment from the file as its program header says and
//! trusts it: a segment that ends past the end of a truncated file is mapped all the same, and
//! the first touch of its missing pages kills the process with SIGBUS (a library cut by `head
//! -c`, or by a copy interrupted halfway). So every program header's bytes, the section header
//! table and every section's bytes must lie within the file, the dynamic segment must be
//! there, and the class, byte order and machine must be this process's; each failure is one
//! line saying what is wrong.
//!
//! The headers are read with the `object` crate (the reader of rustc's and gimli's tool chain,
//! already in the lock file) through its `ReadCache`, which reads only the byte ranges asked
//! for, each checked against the file's length first and allocated fallibly: a header that
//! claims a table larger than the file is an error, not an allocation. Only the headers are
//! read (a few kilobytes): the section header table is capped at [`MAX_SECTIONS`] entries.

use std::fs::File;

use object::elf;
use object::read::elf::{FileHeader, ProgramHeader, SectionHeader};
use object::read::ReadCache;
use object::Endianness;

#[cfg(target_pointer_width = "64")]
type Header = elf::FileHeader64<Endianness>;
#[cfg(target_pointer_width = "32")]
type Header = elf::FileHeader32<Endianness>;

/// This process's ELF class (`EI_CLASS`).
const CLASS: u8 = if cfg!(target_pointer_width = "64") {
    elf::ELFCLASS64
} else {
    elf::ELFCLASS32
};

/// This process's machine (`e_machine`), where toolconf knows it.
const MACHINE: Option<u16> = if cfg!(target_arch = "x86_64") {
    Some(elf::EM_X86_64)
} else if cfg!(target_arch = "aarch64") {
    Some(elf::EM_AARCH64)
} else if cfg!(target_arch = "x86") {
    Some(elf::EM_386)
} else if cfg!(target_arch = "riscv64") {
    Some(elf::EM_RISCV)
} else {
    None
};

/// More sections than any shared library has (a model library has about 40): a header that
/// claims more is damaged, and its table is not read.
const MAX_SECTIONS: usize = 1 << 16;

/// A byte range of the file, named, within its `len` bytes.
fn within(what: &str, offset: u64, size: u64, len: u64) -> Result<(), String> {
    match offset.checked_add(size) {
        Some(end) if end <= len => Ok(()),
        _ => Err(format!(
            "is truncated or damaged: its {what} (bytes {offset} to {}) ends past the file's \
             end ({len} bytes); build it again with make model",
            offset.saturating_add(size)
        )),
    }
}

/// The identification bytes: ELF, this process's class and byte order.
fn identification(ident: &[u8; 6]) -> Result<(), String> {
    if ident[4] != CLASS {
        let bits = if ident[4] == elf::ELFCLASS32 { 32 } else { 64 };
        return Err(format!(
            "is a {bits}-bit ELF file: this process loads {}-bit libraries",
            usize::BITS
        ));
    }
    let native = if cfg!(target_endian = "little") {
        elf::ELFDATA2LSB
    } else {
        elf::ELFDATA2MSB
    };
    if ident[5] != native {
        return Err("is an ELF file of the other byte order than this process's".into());
    }
    Ok(())
}

/// Checks the ELF file `file` of `len` bytes, whose first bytes are `ident`, as the module
/// says.
pub(super) fn check(file: &File, len: u64, ident: &[u8; 6]) -> Result<(), String> {
    identification(ident)?;
    let data = ReadCache::new(file);
    let damaged =
        |what: &str| format!("is truncated or damaged: {what}; build it again with make model");
    let header = Header::parse(&data).map_err(|_| damaged("its ELF header is not whole"))?;
    let endian = header
        .endian()
        .map_err(|_| damaged("its byte order is unreadable"))?;
    if let Some(machine) = MACHINE {
        let theirs = header.e_machine(endian);
        if theirs != machine {
            return Err(format!(
                "is a library for another machine (ELF machine {theirs}; this process's is \
                 {machine})"
            ));
        }
    }
    if header.e_type(endian) != elf::ET_DYN {
        return Err("is an ELF file but not a shared library (make model builds one)".into());
    }
    let segments = header
        .program_headers(endian, &data)
        .map_err(|_| damaged("its program header table is not within the file"))?;
    let mut dynamic = false;
    for (i, s) in segments.iter().enumerate() {
        within(
            &format!("segment {i}"),
            s.p_offset(endian),
            s.p_filesz(endian),
            len,
        )?;
        dynamic |= s.p_type(endian) == elf::PT_DYNAMIC;
    }
    if !dynamic {
        return Err("has no dynamic segment: it is not a shared library".into());
    }
    let count = header
        .shnum(endian, &data)
        .map_err(|_| damaged("its section count is unreadable"))?;
    if count > MAX_SECTIONS {
        return Err(damaged(&format!("it claims {count} sections")));
    }
    let sections = header
        .section_headers(endian, &data)
        .map_err(|_| damaged("its section header table is not within the file"))?;
    for (i, s) in sections.iter().enumerate() {
        if s.sh_type(endian) != elf::SHT_NOBITS {
            within(
                &format!("section {i}"),
                s.sh_offset(endian),
                s.sh_size(endian),
                len,
            )?;
        }
    }
    Ok(())
}
