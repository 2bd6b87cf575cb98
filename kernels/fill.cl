/* Buffer fills (clEnqueueFillBuffer is OpenCL 1.2 but slow on some drivers
 * and not timed by name; these are). */

__kernel void fill_int(__global int* out, const int value, const int count) {
  const int gid = (int)get_global_id(0);
  if (gid < count) out[gid] = value;
}

__kernel void iota_int(__global int* out, const int count) {
  const int gid = (int)get_global_id(0);
  if (gid < count) out[gid] = gid;
}
