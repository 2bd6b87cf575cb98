// Compiles tinygltf's implementation once for luxel_scene (header-only
// library). stb_image comes from libstb (PkgConfig::STB), not from here.
#define TINYGLTF_IMPLEMENTATION
#include "scene/tinygltf_config.h"
