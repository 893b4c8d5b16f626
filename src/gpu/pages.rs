//! Arrays larger than one storage binding. Adapters cap a binding well below the memory
//! they hold (lavapipe: 128 MiB bindings in buffers of up to 2 GiB), so an array of records
//! is kept in one buffer and split into pages of a power-of-two number of records, each page
//! small enough for one binding:
//!
//! - a pass that touches only element i of each array (most per-particle and per-Gaussian
//!   passes) is dispatched once per page, over windows of the buffers
//!   ([`Pages::window`]) and a [`PageRanges`] entry telling it which elements it holds;
//! - a pass that reads elements in any order binds every page and picks one per read
//!   ([`wgsl_paged_reader`]).
//!
//! With one page the windows are the whole buffers, and the passes do exactly what they
//! did before pages existed.

/// How an array of `total` records is split into pages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pages {
    /// Records per page: a power of two.
    pub size: u32,
    /// Number of pages (at least one, so that empty arrays still bind).
    pub count: u32,
    /// Records in all.
    pub total: u32,
}

/// Storage bindings must start at a multiple of this many bytes (wgpu's largest allowed
/// `min_storage_buffer_offset_alignment`); pages start at a multiple of 64 records of ≥ 4
/// bytes, so every window is aligned.
const MIN_PAGE: u32 = 64;

impl Pages {
    /// The largest power-of-two page whose biggest record (`largest_record` bytes) fits a
    /// binding of `max_binding` bytes, for `total` records.
    pub fn new(total: u32, largest_record: u64, max_binding: u64) -> Pages {
        let fit = (max_binding / largest_record.max(1)).clamp(1, 1 << 31);
        let size = (1u64 << (63 - fit.leading_zeros())).max(u64::from(MIN_PAGE)) as u32;
        Self::with_size(total, size)
    }

    /// Pages of `size` records (rounded up to a power of two of at least 64).
    pub fn with_size(total: u32, size: u32) -> Pages {
        let size = size.max(MIN_PAGE).next_power_of_two();
        Pages {
            size,
            count: total.div_ceil(size).max(1),
            total,
        }
    }

    /// log₂ of the page size (the shift from a record index to its page).
    pub fn shift(&self) -> u32 {
        self.size.trailing_zeros()
    }

    /// First record and number of records of page `i`.
    pub fn range(&self, i: u32) -> (u32, u32) {
        let base = i * self.size;
        (base, self.total.saturating_sub(base).min(self.size))
    }

    /// The window of page `i` into `buffer`, whose records are `record` bytes: the whole
    /// buffer when there is one page.
    pub fn window<'a>(
        &self,
        buffer: &'a wgpu::Buffer,
        i: u32,
        record: u64,
    ) -> wgpu::BufferBinding<'a> {
        if self.count == 1 {
            return buffer.as_entire_buffer_binding();
        }
        let (base, len) = self.range(i);
        let offset = u64::from(base) * record;
        let size = (u64::from(len.max(1)) * record).min(buffer.size() - offset);
        wgpu::BufferBinding {
            buffer,
            offset,
            size: wgpu::BufferSize::new(size),
        }
    }
}

/// One `PageRange { base, count }` (WGSL, `shaders/common.wgsl`) per page in one buffer,
/// each at its own aligned slot, for the per-page dispatches to bind.
pub struct PageRanges {
    pub buffer: wgpu::Buffer,
    pub pages: Pages,
}

/// Bytes between two pages' entries (the binding offset alignment).
const SLOT: u64 = 256;

impl PageRanges {
    pub fn new(device: &wgpu::Device, label: &str, pages: Pages) -> PageRanges {
        use wgpu::util::DeviceExt;
        let mut bytes = vec![0u8; (u64::from(pages.count) * SLOT) as usize];
        for i in 0..pages.count {
            let (base, count) = pages.range(i);
            let at = (u64::from(i) * SLOT) as usize;
            bytes[at..at + 8].copy_from_slice(bytemuck::bytes_of(&[base, count]));
        }
        let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: &bytes,
            usage: wgpu::BufferUsages::STORAGE,
        });
        PageRanges { buffer, pages }
    }

    /// Page `i`'s entry, to bind as the pass's `page`.
    pub fn entry(&self, i: u32) -> wgpu::BufferBinding<'_> {
        wgpu::BufferBinding {
            buffer: &self.buffer,
            offset: u64::from(i) * SLOT,
            size: wgpu::BufferSize::new(8),
        }
    }
}

/// The WGSL name of page `k` of the paged array `name` (as [`wgsl_paged_reader`] declares
/// it), to bind it by name.
pub fn page_var(name: &str, k: u32) -> String {
    format!("{name}_{k}")
}

/// WGSL declaring `pages` read-only bindings `NAME_0 … NAME_{pages-1}` of `array<TY>` from
/// binding `first`, and `fn NAME_at(i: u32) -> TY` reading record i from its page, with
/// page size `1 << SHIFT` where SHIFT is the WGSL expression `shift`.
pub fn wgsl_paged_reader(name: &str, ty: &str, first: u32, pages: u32, shift: &str) -> String {
    if pages <= 1 {
        return format!(
            "@group(0) @binding({first}) var<storage, read> {name}_0: array<{ty}>;\nfn {name}_at(i: u32) -> {ty} {{\n    return {name}_0[i];\n}}\n"
        );
    }
    let mut s = String::new();
    for k in 0..pages {
        s += &format!(
            "@group(0) @binding({}) var<storage, read> {}: array<{ty}>;\n",
            first + k,
            page_var(name, k)
        );
    }
    s += &format!(
        "fn {name}_at(i: u32) -> {ty} {{\n    let page = i >> {shift};\n    let j = i & ((1u << {shift}) - 1u);\n    switch page {{\n"
    );
    for k in 1..pages {
        s += &format!("        case {k}u: {{ return {name}_{k}[j]; }}\n");
    }
    s += &format!("        default: {{ return {name}_0[j]; }}\n    }}\n}}\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pages_cover_every_record_once_within_the_binding() {
        let p = Pages::new(6_000_000, 96, 128 << 20);
        assert_eq!(p.size, 1 << 20);
        assert!(u64::from(p.size) * 96 <= 128 << 20);
        assert_eq!(p.count, 6);
        let mut covered = 0;
        for i in 0..p.count {
            let (base, n) = p.range(i);
            assert_eq!(base, covered);
            covered += n;
        }
        assert_eq!(covered, 6_000_000);
        assert_eq!(Pages::new(0, 48, 128 << 20).count, 1);
        assert_eq!(
            Pages::with_size(1000, 100),
            Pages {
                size: 128,
                count: 8,
                total: 1000
            }
        );
    }

    #[test]
    fn the_paged_reader_parses_and_declares_each_page() {
        let src = format!(
            "{}\n@group(0) @binding(0) var<storage, read_write> out: array<f32>;\n@compute @workgroup_size(1) fn main() {{ out[0] = v_at(5u); }}",
            wgsl_paged_reader("v", "f32", 1, 3, "4u")
        );
        let module = wgpu::naga::front::wgsl::parse_str(&src).expect("parses");
        let names: Vec<_> = module
            .global_variables
            .iter()
            .filter_map(|(_, g)| g.name.clone())
            .collect();
        for n in ["v_0", "v_1", "v_2"] {
            assert!(names.iter().any(|m| m == n), "{names:?}");
        }
    }
}
