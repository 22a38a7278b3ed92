#pragma once
/// \file The standard models: their names, where their mesh files are looked for, and how they
/// are fetched from Debian's libcgal-demo data archive into the user's data folder.
///
/// Where models live (first folder that has the file wins):
///   1. $NBV_MODELS_DIR, if set (and then only there);
///   2. the user's data folder, $XDG_DATA_HOME/nbv/models (default ~/.local/share/nbv/models),
///      where fetchStandardModels() writes;
///   3. each of $XDG_DATA_DIRS (default /usr/local/share:/usr/share) followed by nbv/models, for
///      a copy shared by every user of a machine.
///
/// Thread-safety: every function reads the environment and the file system only, and may run
/// in several threads at once; fetchStandardModels() writes each file under a temporary name
/// and renames it, so a reader never sees half a mesh.

#include "nbv/errors.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace nbv::sensor {

/// Which axis of a mesh file points up (SEMANTICS.md "Scene conditions").
enum class UpAxis {
  Z,  ///< as stored: the file's z is the world's up
  Y,  ///< y-up: turned +90 degrees about x before placement, so the file's y becomes z
};

/// A standard model: the short name, its file in the CGAL data set, and the axis its file
/// stores as up (seen in renders of both orientations).
struct StandardModel {
  std::string name;
  std::string file;
  UpAxis stored_up = UpAxis::Z;
};

/// The 11 standard models: bunny, armadillo, dragon, dino, head (the first five), bull,
/// mannequin-devil, nefertiti, elk, pig, diplodocus.
const std::vector<StandardModel>& standardModels();

/// The folders standard models are looked for in, in order (the file comment says which).
/// \throws InvalidArgument if neither NBV_MODELS_DIR, XDG_DATA_HOME nor HOME names a folder.
std::vector<std::filesystem::path> modelSearchPath();

/// The folder fetchStandardModels() writes to by default: $NBV_MODELS_DIR if set, else the
/// user's data folder ($XDG_DATA_HOME/nbv/models or ~/.local/share/nbv/models).
/// \throws InvalidArgument if neither NBV_MODELS_DIR, XDG_DATA_HOME nor HOME is set.
std::filesystem::path userModelsDir();

/// The file of a model: a short name of standardModels() resolves to its file in the first
/// folder of `search` that has it; anything else is taken as a path.
/// \throws MeshFileError if the file does not exist: for a short name, naming the folders
/// searched and the command that fetches the models; for anything else, listing the short
/// names.
std::filesystem::path resolveModel(const std::string& name_or_path,
                                   const std::vector<std::filesystem::path>& search = modelSearchPath());

/// Where fetchStandardModels() takes the meshes from and puts them.
struct FetchOptions {
  /// The folder to write; empty: userModelsDir().
  std::filesystem::path dir;
  /// A libcgal-demo .deb, or the data.tar.gz inside it; empty: the installed package's archive
  /// if libcgal-demo is installed, else a .deb in apt's cache, else `apt-get download`.
  std::filesystem::path source;
};

/// What fetchStandardModels() did.
struct FetchReport {
  std::filesystem::path dir;         ///< the folder that now holds every standard model
  std::string source;                ///< the archive the meshes came from (empty if none was needed)
  std::vector<std::string> written;  ///< the files written (those already there are kept)
};

/// Puts the 11 standard meshes into `options.dir`, extracted from the data archive of
/// Debian's libcgal-demo (no package is installed: the .deb is downloaded with `apt-get
/// download` when no archive is at hand). Files already there are kept. Runs apt-get, dpkg-deb
/// and tar, waiting for them.
/// \throws FileError naming the folder or archive, with what the tool printed, if the archive
/// cannot be had or read, or the folder written.
FetchReport fetchStandardModels(const FetchOptions& options = {});

}  // namespace nbv::sensor
