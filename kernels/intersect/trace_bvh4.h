/* Closest- and any-hit traversal of the BVH4 (kernels/shared/geometry.h,
 * LuxBvh4Node). Included by intersect.cl when LUX_BVH4 is on; the caller
 * defines LUX_ALPHA_PARAMS / LUX_ALPHA_ACCEPT.
 *
 * One work-item per ray, as for the BVH2, but each node fetch tests all four
 * child boxes with float4 operations: the SoA layout puts one plane of the
 * four boxes in one float4, so the slab test is six float4 subtract-multiply
 * pairs and the reductions are float4 min/max (Ernst & Greiner 2008, "Multi
 * Bounding Volume Hierarchies"; Wald, Benthin and Boulos 2008, "Getting Rid
 * of Packets", single-ray SIMD traversal of a 4-ary BVH). PoCL compiles the
 * work-item loop to scalar code, so this is where its SIMD lanes are used.
 *
 * Per ray, the octant of the direction picks which plane of each slab is
 * entered first, so no per-axis min/max of the two plane distances is needed
 * (the sign of the reciprocal orders them; rounding is monotonic, so the
 * result equals the BVH2's fmin/fmax form). Box tests stay conservative as
 * in traverse.h (Ize 2013): the exit distance is scaled by
 * LUX_BOX_EXIT_SCALE.
 *
 * Order: the children a ray enters are sorted by entry distance (a 4-input
 * sorting network) and pushed farthest first with their entry distance;
 * popping re-checks the distance against the closest hit, so subtrees and
 * leaves behind it are skipped. Leaves are stack entries too, encoded as
 * ~(node * 4 + slot), so traversal is strictly front to back (as Embree's
 * BVH4 traversal). */

/* Element-wise max/min without the NaN rules of fmax/fmin (no NaN reaches
 * them: the safe reciprocal is never 0 and plane distances are finite or
 * +-INFINITY for absent slots). */
#define LUX_MAX4(a, b) select((b), (a), (a) > (b))
#define LUX_MIN4(a, b) select((b), (a), (a) < (b))

/* Orders (ta, ra) <= (tb, rb) by distance. */
#define LUX_SORT2(ta, ra, tb, rb) \
  do {                            \
    if ((tb) < (ta)) {            \
      const float t_ = (ta);      \
      (ta) = (tb);                \
      (tb) = t_;                  \
      const int r_ = (ra);        \
      (ra) = (rb);                \
      (rb) = r_;                  \
    }                             \
  } while (0)

/* Traverses for ray `ray`; writes the closest (or any) hit. Returns the
 * original triangle id or -1. */
inline int lux_trace(__global const LuxBvh4Node* nodes,
                     __global const LuxTriangle* tris LUX_ALPHA_PARAMS, const LuxRay ray,
                     int any_hit, float* t_out, float* u_out, float* v_out) {
  const float3 org = ray.org_tmin.xyz;
  const float3 dir = ray.dir_tmax.xyz;
  const float tmin = ray.org_tmin.w;
  float t_best = ray.dir_tmax.w;
  const float3 inv_dir = lux_safe_inv_dir(dir);
  const LuxRayShear shear = lux_ray_shear(org, dir);
  const int neg_x = inv_dir.x < 0.0f, neg_y = inv_dir.y < 0.0f, neg_z = inv_dir.z < 0.0f;
  const float4 ox = (float4)(org.x), oy = (float4)(org.y), oz = (float4)(org.z);
  const float4 ix = (float4)(inv_dir.x), iy = (float4)(inv_dir.y), iz = (float4)(inv_dir.z);
  const float4 tmin4 = (float4)(tmin);
  const float4 inf4 = (float4)(INFINITY);
  const int4 slot4 = (int4)(0, 1, 2, 3);

  int hit_prim = -1;
  float hit_u = 0.0f, hit_v = 0.0f;
  int stack_ref[LUX_STACK_SIZE];
  float stack_t[LUX_STACK_SIZE];
  int sp = 0;
  int ref = 0; /* the root */

  for (;;) {
    if (ref >= 0) {
      __global const LuxBvh4Node* n = &nodes[ref];
      const float4 near_x = neg_x ? n->hi_x : n->lo_x, far_x = neg_x ? n->lo_x : n->hi_x;
      const float4 near_y = neg_y ? n->hi_y : n->lo_y, far_y = neg_y ? n->lo_y : n->hi_y;
      const float4 near_z = neg_z ? n->hi_z : n->lo_z, far_z = neg_z ? n->lo_z : n->hi_z;
      const float4 tnx = (near_x - ox) * ix, tfx = (far_x - ox) * ix;
      const float4 tny = (near_y - oy) * iy, tfy = (far_y - oy) * iy;
      const float4 tnz = (near_z - oz) * iz, tfz = (far_z - oz) * iz;
      const float4 enter = LUX_MAX4(LUX_MAX4(tnx, tny), LUX_MAX4(tnz, tmin4));
      const float4 exit =
          LUX_MIN4(LUX_MIN4(tfx, tfy), LUX_MIN4(tfz, (float4)(t_best))) * LUX_BOX_EXIT_SCALE;
      /* Missed slots (absent ones included: their entry is +INFINITY or the
       * slab test fails) get +INFINITY and sort last. */
      const float4 t4 = select(inf4, enter, (enter <= exit) & (enter <= (float4)(t_best)));
      const int4 count = n->count;
      const int4 ref4 = select(n->child, ~((int4)(ref * 4) + slot4), count > 0);
      float t0 = t4.x, t1 = t4.y, t2 = t4.z, t3 = t4.w;
      int r0 = ref4.x, r1 = ref4.y, r2 = ref4.z, r3 = ref4.w;
      if (!any_hit) {
        /* Optimal 4-input sorting network (Knuth, TAOCP 3, §5.3.4). */
        LUX_SORT2(t0, r0, t1, r1);
        LUX_SORT2(t2, r2, t3, r3);
        LUX_SORT2(t0, r0, t2, r2);
        LUX_SORT2(t1, r1, t3, r3);
        LUX_SORT2(t1, r1, t2, r2);
      }
      /* Farthest first, so the nearest is popped next. Overflow drops
       * entries; the host sizes LUX_STACK_SIZE so it cannot happen. */
      if (t3 < INFINITY && sp < LUX_STACK_SIZE) {
        stack_ref[sp] = r3;
        stack_t[sp++] = t3;
      }
      if (t2 < INFINITY && sp < LUX_STACK_SIZE) {
        stack_ref[sp] = r2;
        stack_t[sp++] = t2;
      }
      if (t1 < INFINITY && sp < LUX_STACK_SIZE) {
        stack_ref[sp] = r1;
        stack_t[sp++] = t1;
      }
      /* The nearest is visited at once, without a stack round trip. */
      if (t0 < INFINITY) {
        ref = r0;
        continue;
      }
    } else {
      const int leaf = ~ref;
      __global const int* slots = (__global const int*)&nodes[leaf >> 2].child;
      const int first = slots[leaf & 3];
      const int count = slots[4 + (leaf & 3)]; /* count follows child */
      LUX_INTERSECT_LEAF(first, count);
    }
    /* Pop, skipping subtrees and leaves that start behind the closest hit. */
    int found = 0;
    while (sp > 0) {
      --sp;
      if (stack_t[sp] <= t_best) {
        ref = stack_ref[sp];
        found = 1;
        break;
      }
    }
    if (!found) break;
  }
  *t_out = t_best;
  *u_out = hit_u;
  *v_out = hit_v;
  return hit_prim;
}

#undef LUX_SORT2
#undef LUX_MIN4
#undef LUX_MAX4
