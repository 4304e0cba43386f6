// The offline view's input: a Wavefront OBJ mesh as tachi-sim --export writes it (v, vt, f with
// v/vt indices, one `g`/`o` group per piece), read into the renderer's Mesh with one group per
// `g`/`o` name so pieces are drawn in different shades. Polygons are split into triangle fans;
// texture coordinates and normals are ignored.
#pragma once

#include "tachi/viewer/render.hpp"

#include <filesystem>
#include <optional>
#include <string>

namespace tachi::viewer {

/// The mesh in `file`, or nothing with `error` naming the file and line (unreadable file, a bad
/// number, an index out of range, a non-finite coordinate, no faces at all).
std::optional<Mesh> read_obj(const std::filesystem::path& file, std::string& error);

/// A view of the same size that frames `mesh`: the part hanging near its top (pieces that fell far
/// below would shrink the cloth to a speck; they stay drawn when they are in view).
View framing(const Mesh& mesh, View view);

}  // namespace tachi::viewer
