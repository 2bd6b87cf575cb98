"""The scene generator behind scenes/generate_scenes.py: gltf_writer (the glTF
writer), geometry (math helpers, chart packer, MeshBuilder) and one module per
bundled scene."""
