#pragma once

#include <cstddef>
#include <string>

namespace rastercheck::detail
{
/** \brief Whether assimp's PLY reader would take \a data for a PLY file: "ply" in any case after
    leading blanks. */
bool looksLikePly(const char *data, std::size_t size);

/** \brief Checks a PLY file before assimp 5.2.5 reads it, which it cannot do safely: on a header
    without `end_header` it never returns, and it allocates what the file declares (element counts,
    list lengths: "element vertex 4000000000", a list count of -1 read as 4294967295) before reading
    it (all found by fuzz_mesh). Accepts the header form exporters write — `ply`, `format ascii |
    binary_little_endian | binary_big_endian V`, comment/obj_info lines before the first element,
    `element NAME COUNT`, `property TYPE NAME`, `property list INTTYPE TYPE NAME`, `end_header` — in
    the lines assimp reads, then walks the body as assimp will and requires every element instance
    and every list to be there in full. Throws InputError naming \a name and the header line or the
    element otherwise. */
void checkPly(const char *data, std::size_t size, const std::string &name);
}  // namespace rastercheck::detail
