/* Closest- and any-hit traversal of the fat BVH2 (kernels/shared/geometry.h,
 * LuxBvhNode). Included by intersect.cl when LUX_BVH4 is off; the caller
 * defines LUX_ALPHA_PARAMS / LUX_ALPHA_ACCEPT. */

/* Traverses for ray `ray`; writes the closest (or any) hit. Returns the
 * original triangle id or -1. */
inline int lux_trace(__global const LuxBvhNode* nodes,
                     __global const LuxTriangle* tris LUX_ALPHA_PARAMS, const LuxRay ray,
                     int any_hit, float* t_out, float* u_out, float* v_out) {
  const float3 org = ray.org_tmin.xyz;
  const float3 dir = ray.dir_tmax.xyz;
  const float tmin = ray.org_tmin.w;
  float t_best = ray.dir_tmax.w;
  const float3 inv_dir = lux_safe_inv_dir(dir);
  const LuxRayShear shear = lux_ray_shear(org, dir);

  int hit_prim = -1;
  float hit_u = 0.0f, hit_v = 0.0f;
  int stack_node[LUX_STACK_SIZE];
  float stack_t[LUX_STACK_SIZE];
  int sp = 0;
  int node = 0;

  for (;;) {
    const LuxBvhNode n = nodes[node];
    float tl = lux_box_entry(n.lmin, n.lmax, org, inv_dir, tmin, t_best);
    float tr = lux_box_entry(n.rmin, n.rmax, org, inv_dir, tmin, t_best);
    const int lref = as_int(n.lmin.w), lcount = as_int(n.lmax.w);
    const int rref = as_int(n.rmin.w), rcount = as_int(n.rmax.w);
    /* An absent child (ref -1) is never entered: the slab test alone would
     * accept its inverted bounds. */
    if (lref < 0) tl = INFINITY;
    if (rref < 0) tr = INFINITY;

    /* Leaves are tested in place, nearer first. */
    const int first_left = tl <= tr;
    for (int side = 0; side < 2; ++side) {
      const int left = (side == 0) == first_left;
      const int count = left ? lcount : rcount;
      const float entry = left ? tl : tr;
      if (count == 0 || !(entry <= t_best) || entry == INFINITY) continue;
      const int first = left ? lref : rref;
      LUX_INTERSECT_LEAF(first, count);
      if (left)
        tl = INFINITY;
      else
        tr = INFINITY;
    }

    /* INFINITY marks a missed (or already tested leaf) child; t_best may
     * itself be INFINITY before the first hit. */
    const int go_l = tl < INFINITY && tl <= t_best;
    const int go_r = tr < INFINITY && tr <= t_best;
    if (go_l && go_r) {
      const int near_left = tl <= tr;
      if (sp < LUX_STACK_SIZE) {
        stack_node[sp] = near_left ? rref : lref;
        stack_t[sp] = near_left ? tr : tl;
        ++sp;
      }
      node = near_left ? lref : rref;
      continue;
    }
    if (go_l) {
      node = lref;
      continue;
    }
    if (go_r) {
      node = rref;
      continue;
    }
    /* Pop, skipping subtrees that start behind the closest hit. */
    node = -1;
    while (sp > 0) {
      --sp;
      if (stack_t[sp] <= t_best) {
        node = stack_node[sp];
        break;
      }
    }
    if (node < 0) break;
  }
  *t_out = t_best;
  *u_out = hit_u;
  *v_out = hit_v;
  return hit_prim;
}
