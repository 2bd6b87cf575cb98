// Reads a scene with Assimp (Debian's libassimp, the library behind
// assimp-utils) and prints what the write-back round trip compares, as JSON:
// per mesh (Assimp makes one per glTF primitive, in file order) its name,
// positions, faces and every texture coordinate channel; per material the UV
// channel each texture reads ($tex.uvwsrc). `assimp export -fassjson` would
// print the same, but its scene copy asserts on glTF extras arrays (Assimp
// 5.2's SceneCombiner), so the import itself is read here.
// Usage: assimp_dump FILE   (exit 1 and Assimp's message when it refuses)
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cstdio>
#include <cstring>
#include <string>

namespace {

void print_floats(const char* sep, float v) {
  std::printf("%s%.7g", sep, static_cast<double>(v));
}

std::string quoted(const char* s) {
  std::string out = "\"";
  for (; *s; ++s) {
    if (*s == '"' || *s == '\\') out += '\\';
    if (static_cast<unsigned char>(*s) >= 0x20) out += *s;
  }
  return out + "\"";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: assimp_dump FILE\n");
    return 2;
  }
  const aiScene* scene = aiImportFile(argv[1], aiProcess_ValidateDataStructure);
  if (!scene) {
    std::fprintf(stderr, "assimp refuses %s: %s\n", argv[1], aiGetErrorString());
    return 1;
  }
  std::printf("{\"meshes\": [");
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    std::printf("%s{\"name\": %s, \"vertices\": [", m ? ", " : "",
                quoted(mesh->mName.C_Str()).c_str());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v)
      for (int k = 0; k < 3; ++k) print_floats(v || k ? ", " : "", mesh->mVertices[v][k]);
    std::printf("], \"faces\": [");
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      std::printf("%s[", f ? ", " : "");
      for (unsigned i = 0; i < mesh->mFaces[f].mNumIndices; ++i)
        std::printf("%s%u", i ? ", " : "", mesh->mFaces[f].mIndices[i]);
      std::printf("]");
    }
    std::printf("], \"uv\": [");
    for (unsigned c = 0; c < AI_MAX_NUMBER_OF_TEXTURECOORDS && mesh->mTextureCoords[c]; ++c) {
      std::printf("%s[", c ? ", " : "");
      for (unsigned v = 0; v < mesh->mNumVertices; ++v)
        for (int k = 0; k < 2; ++k) print_floats(v || k ? ", " : "", mesh->mTextureCoords[c][v][k]);
      std::printf("]");
    }
    std::printf("]}");
  }
  std::printf("], \"materials\": [");
  for (unsigned m = 0; m < scene->mNumMaterials; ++m) {
    const aiMaterial* mat = scene->mMaterials[m];
    std::printf("%s[", m ? ", " : "");
    bool first = true;
    for (unsigned p = 0; p < mat->mNumProperties; ++p) {
      const aiMaterialProperty* prop = mat->mProperties[p];
      if (std::string(prop->mKey.C_Str()) != "$tex.uvwsrc" || prop->mDataLength < 4) continue;
      int channel = 0;
      std::memcpy(&channel, prop->mData, 4);
      std::printf("%s[%u, %u, %d]", first ? "" : ", ", prop->mSemantic, prop->mIndex, channel);
      first = false;
    }
    std::printf("]");
  }
  std::printf("]}\n");
  aiReleaseImport(scene);
  return 0;
}
