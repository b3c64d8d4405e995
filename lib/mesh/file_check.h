// Format checks that run before OpenMesh's readers (lib/mesh internal; see loadMesh in mesh.h for why).
// They parse only to check: declared counts against the data present, every number, text being text. The mesh
// itself comes from OpenMesh.
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <string_view>

namespace prt::detail {

inline constexpr size_t kUnknownCount = std::numeric_limits<size_t>::max();

// What a file declares, for comparison with what OpenMesh's reader returns.
struct CheckedFile {
    size_t vertices = kUnknownCount; // unknown for STL, whose reader shares vertices itself
    size_t faces = 0;
    size_t facesWithoutTriangle = 0; // faces the reader skips: fewer than three distinct corners (OBJ, STL)
    bool binary = false;             // STL: the reader must be told
    // When not empty, what OpenMesh reads instead of the file: the same content without the parts its readers
    // misparse (OFF comments; PLY headers are rewritten in the plain form its parser expects).
    std::string readerInput;
};

// Removes a leading UTF-8 byte order mark (EF BB BF, which Windows editors write) from a text file's bytes: the
// readers would take it for part of the first line's keyword and skip that line. Returns whether there was one.
bool dropUtf8Bom(std::string& text);

// Each throws prt::Error naming `path`, the place (line, element, byte offset) and the problem.
CheckedFile checkObj(std::string_view text, const std::string& path);
CheckedFile checkOff(std::string_view text, const std::string& path);
CheckedFile checkPly(std::string_view bytes, const std::string& path);
CheckedFile checkStl(std::string_view bytes, const std::string& path);

} // namespace prt::detail
