// Depth only (meshes into shadow maps).
void main() {}
