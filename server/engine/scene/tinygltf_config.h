// The one place that includes tiny_gltf.h, so every translation unit sees the
// same configuration.
//
// tinygltf's own stb-based image decoding is switched off: the importer keeps
// the encoded bytes (see gltf_load.cpp) and decodes them itself with size
// limits checked before any pixel memory is allocated (textures.cpp). Image
// writing is never used.
#pragma once

#ifndef TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE
#endif
#ifndef TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#endif

#include <tiny_gltf.h>
