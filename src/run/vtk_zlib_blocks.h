// VTK XML's appended raw binary data, compressed as vtkZLibDataCompressor does: an array's
// bytes cut into blocks of 32 KiB, each compressed by zlib, after a header of UInt64 words
// [block count, block size, size of the last block (0: a full one), compressed size of each
// block]. The snapshots write it (output.snapshot_format = "binary"), the frames read it.
#pragma once
#include <cstddef>
#include <string>
#include <string_view>

namespace demlab {

inline constexpr size_t kVtkBlockBytes = 32768;

// Appends the header and the compressed blocks of bytes[0, size) to out.
void append_zlib_blocks(std::string& out, const void* bytes, size_t size);

// The bytes of the array whose header starts at `offset` of the appended data (after its
// "_"); path names the file in the InputError of a truncated or corrupt array.
std::string read_zlib_blocks(std::string_view appended, size_t offset, const std::string& path);

}  // namespace demlab
