// emit_c.hpp -- a terrain package as C source: NAME.c / NAME.h holding the
// package's exact bytes as an 8-byte-aligned const array, for linking into
// firmware (ct_package_open reads it in place, from flash).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ct_host {

// Writes <dir>/NAME.c and <dir>/NAME.h, dir = the directory of package_path,
// from the package file (read in chunks).  NAME must be a C identifier.
// Throws Error (file, reason); each file is written atomically (never a
// partial file), and both or neither.
void emit_c_array(const std::string &package_path, const std::string &name);

// true when s is a valid C identifier (and not too long for C99's 31
// significant characters of external names)
bool is_c_identifier(const std::string &s);

}  // namespace ct_host
