/* Material texture fetches (device side). See shared/texture.h for the
 * layout. Filtering is bilinear; wrapping follows the texture's sampler
 * (glTF 2.0 §5.26: REPEAT, CLAMP_TO_EDGE, MIRRORED_REPEAT, applied to the
 * integer texel indices as OpenGL 4.6 §8.14.2 Table 8.20 defines them); glTF
 * UV (0,0) is the top-left corner of row 0. sRGB texels are decoded to
 * linear BEFORE filtering, so the filter averages light, not encoded
 * values. */
#ifndef LUXEL_SHADING_TEXTURE_H
#define LUXEL_SHADING_TEXTURE_H

#include "shared/texture.h"

/* The exact sRGB EOTF (IEC 61966-2-1) at k / 255, k = 0..255: an 8-bit
 * texel's decode is exact and costs one table read. */
__constant float lux_srgb_to_linear_table[256] = {
    0.0f,           0.000303526984f, 0.000607053967f, 0.000910580951f, 0.00121410793f,
    0.00151763492f, 0.0018211619f,   0.00212468888f,  0.00242821587f,  0.00273174285f,
    0.00303526984f, 0.00334653576f,  0.00367650732f,  0.00402471702f,  0.00439144204f,
    0.00477695348f, 0.0051815167f,   0.00560539162f,  0.00604883302f,  0.00651209079f,
    0.00699541019f, 0.00749903204f,  0.00802319299f,  0.00856812562f,  0.0091340587f,
    0.00972121732f, 0.010329823f,    0.010960094f,    0.0116122452f,   0.0122864884f,
    0.0129830323f,  0.013702083f,    0.0144438436f,   0.0152085144f,   0.0159962934f,
    0.0168073758f,  0.0176419545f,   0.0185002201f,   0.019382361f,    0.0202885631f,
    0.0212190104f,  0.0221738848f,   0.0231533662f,   0.0241576324f,   0.0251868596f,
    0.0262412219f,  0.0273208916f,   0.0284260395f,   0.0295568344f,   0.0307134437f,
    0.0318960331f,  0.0331047666f,   0.0343398068f,   0.0356013149f,   0.0368894504f,
    0.0382043716f,  0.0395462353f,   0.0409151969f,   0.0423114106f,   0.0437350293f,
    0.0451862044f,  0.0466650863f,   0.0481718242f,   0.049706566f,    0.0512694584f,
    0.052860647f,   0.0544802764f,   0.05612849f,     0.0578054302f,   0.0595112382f,
    0.0612460542f,  0.0630100177f,   0.0648032667f,   0.0666259386f,   0.0684781698f,
    0.0703600957f,  0.0722718507f,   0.0742135684f,   0.0761853815f,   0.0781874218f,
    0.0802198203f,  0.0822827071f,   0.0843762115f,   0.086500462f,    0.0886555863f,
    0.0908417112f,  0.0930589628f,   0.0953074666f,   0.0975873471f,   0.0998987282f,
    0.102241733f,   0.104616484f,    0.107023103f,    0.109461711f,    0.111932428f,
    0.114435374f,   0.116970668f,    0.119538428f,    0.122138772f,    0.124771818f,
    0.12743768f,    0.130136477f,    0.132868322f,    0.13563333f,     0.138431615f,
    0.141263291f,   0.144128471f,    0.147027266f,    0.14995979f,     0.152926152f,
    0.155926464f,   0.158960835f,    0.162029376f,    0.165132195f,    0.1682694f,
    0.171441101f,   0.174647404f,    0.177888416f,    0.181164244f,    0.184474995f,
    0.187820772f,   0.191201683f,    0.19461783f,     0.19806932f,     0.201556254f,
    0.205078736f,   0.20863687f,     0.212230757f,    0.2158605f,      0.2195262f,
    0.223227957f,   0.226965874f,    0.230740049f,    0.234550582f,    0.238397574f,
    0.242281122f,   0.246201327f,    0.250158285f,    0.254152094f,    0.258182853f,
    0.262250658f,   0.266355605f,    0.270497791f,    0.274677312f,    0.278894263f,
    0.28314874f,    0.287440838f,    0.29177065f,     0.296138271f,    0.300543794f,
    0.304987314f,   0.309468923f,    0.313988713f,    0.318546778f,    0.323143209f,
    0.327778098f,   0.332451536f,    0.337163615f,    0.341914425f,    0.346704056f,
    0.3515326f,     0.356400144f,    0.36130678f,     0.366252596f,    0.37123768f,
    0.376262123f,   0.381326011f,    0.386429434f,    0.391572478f,    0.396755231f,
    0.40197778f,    0.407240212f,    0.412542613f,    0.417885071f,    0.42326767f,
    0.428690497f,   0.434153636f,    0.439657174f,    0.445201195f,    0.450785783f,
    0.456411023f,   0.462077f,       0.467783796f,    0.473531496f,    0.479320183f,
    0.48514994f,    0.49102085f,     0.496932995f,    0.502886458f,    0.508881321f,
    0.514917665f,   0.520995573f,    0.527115126f,    0.533276404f,    0.539479489f,
    0.545724461f,   0.552011402f,    0.55834039f,     0.564711506f,    0.571124829f,
    0.57758044f,    0.584078418f,    0.590618841f,    0.597201788f,    0.603827339f,
    0.610495571f,   0.617206562f,    0.623960392f,    0.630757136f,    0.637596874f,
    0.644479682f,   0.651405637f,    0.658374817f,    0.665387298f,    0.672443157f,
    0.67954247f,    0.686685312f,    0.693871761f,    0.701101892f,    0.70837578f,
    0.715693501f,   0.723055129f,    0.73046074f,     0.737910409f,    0.74540421f,
    0.752942217f,   0.760524505f,    0.768151147f,    0.775822218f,    0.783537792f,
    0.79129794f,    0.799102738f,    0.806952258f,    0.814846572f,    0.822785754f,
    0.830769877f,   0.838799012f,    0.846873232f,    0.854992608f,    0.863157213f,
    0.871367119f,   0.879622397f,    0.887923118f,    0.896269353f,    0.904661174f,
    0.913098652f,   0.921581856f,    0.930110858f,    0.938685728f,    0.947306537f,
    0.955973353f,   0.964686248f,    0.97344529f,     0.98225055f,     0.991102097f,
    1.0f,
};

/* One texel as linear RGBA, integer coordinates already wrapped. */
inline float4 lux_texture_texel(const __global uint* texels, LuxTexture t, int x, int y) {
  if (t.flags & LUX_TEXTURE_FLAG_HALF)
    return vload_half4((size_t)(y * t.width + x), (const __global half*)(texels + t.offset));
  const uint w = texels[t.offset + y * t.width + x];
  const uint r = w & 0xffu, g = (w >> 8) & 0xffu, b = (w >> 16) & 0xffu, a = w >> 24;
  if (t.flags & LUX_TEXTURE_FLAG_SRGB) {
    return (float4)(lux_srgb_to_linear_table[r], lux_srgb_to_linear_table[g],
                    lux_srgb_to_linear_table[b], (float)a * (1.0f / 255.0f));
  }
  return convert_float4((uint4)(r, g, b, a)) * (1.0f / 255.0f);
}

/* Repeat wrap of an integer texel coordinate into [0, n). */
inline int lux_texture_wrap(int i, int n) {
  const int m = i % n;
  return m < 0 ? m + n : m;
}

/* An integer texel coordinate under wrap `mode` (Table 8.20): clamp; repeat
 * mod n; mirrored repeat: i mod 2n, reflected in its second half. */
inline int lux_texture_wrap_mode(int i, int n, int mode) {
  if (mode == LUX_WRAP_CLAMP) return clamp(i, 0, n - 1);
  if (mode == LUX_WRAP_MIRROR) {
    const int m = lux_texture_wrap(i, 2 * n);
    return m < n ? m : 2 * n - 1 - m;
  }
  return lux_texture_wrap(i, n);
}

/* A texture coordinate reduced to one period of its wrap before scaling, so
 * large coordinates keep their sub-texel precision and the int conversion
 * cannot overflow: [0, 1) for repeat, [0, 2) for mirrored repeat (its
 * period), [0, 1] for clamp (every coordinate past an edge reads the edge
 * texel, so clamping first changes nothing). NaN and infinities read 0. */
inline float lux_texture_reduce(float u, int mode) {
  if (mode == LUX_WRAP_CLAMP) return (u >= 0.0f) ? fmin(u, 1.0f) : 0.0f;
  const float f = mode == LUX_WRAP_MIRROR ? u - 2.0f * floor(0.5f * u) : u - floor(u);
  return (f >= 0.0f && f <= 2.0f) ? f : 0.0f;
}

/* Bilinear sample at uv with wrap modes (wrap_s, wrap_t); linear RGBA.
 * Texel (x, y) covers uv [x/w, (x+1)/w) x [y/h, (y+1)/h), its centre at
 * (x+0.5)/w. */
inline float4 lux_texture_sample_wrap(const __global uint* texels, LuxTexture t, float2 uv,
                                      int wrap_s, int wrap_t) {
  const float x = lux_texture_reduce(uv.x, wrap_s) * (float)t.width - 0.5f;
  const float y = lux_texture_reduce(uv.y, wrap_t) * (float)t.height - 0.5f;
  const float x0f = floor(x), y0f = floor(y);
  const float fx = x - x0f, fy = y - y0f;
  const int x0 = lux_texture_wrap_mode((int)x0f, t.width, wrap_s),
            x1 = lux_texture_wrap_mode((int)x0f + 1, t.width, wrap_s);
  const int y0 = lux_texture_wrap_mode((int)y0f, t.height, wrap_t),
            y1 = lux_texture_wrap_mode((int)y0f + 1, t.height, wrap_t);
  const float4 top =
      mix(lux_texture_texel(texels, t, x0, y0), lux_texture_texel(texels, t, x1, y0), fx);
  const float4 bottom =
      mix(lux_texture_texel(texels, t, x0, y1), lux_texture_texel(texels, t, x1, y1), fx);
  return mix(top, bottom, fy);
}

/* Bilinear sample with repeat wrapping (the glTF default sampler). */
inline float4 lux_texture_sample(const __global uint* texels, LuxTexture t, float2 uv) {
  return lux_texture_sample_wrap(texels, t, uv, LUX_WRAP_REPEAT, LUX_WRAP_REPEAT);
}

/* The UV a material slot reads: its UV set, then KHR_texture_transform's
 * uv' = T * R * S * (u, v, 1) (the matrix built on the host). */
inline float2 lux_texture_slot_uv(LuxTextureSlot s, float2 uv0, float2 uv1) {
  const float2 uv = (s.flags & LUX_SLOT_TEXCOORD1) ? uv1 : uv0;
  if (!(s.flags & LUX_SLOT_TRANSFORM)) return uv;
  return (float2)(s.m00 * uv.x + s.m01 * uv.y + s.m02, s.m10 * uv.x + s.m11 * uv.y + s.m12);
}

/* Texture of material slot s at a surface point with UV sets uv0, uv1. */
inline float4 lux_texture_slot_sample(const __global uint* texels,
                                      const __global LuxTexture* textures, LuxTextureSlot s,
                                      float2 uv0, float2 uv1) {
  return lux_texture_sample_wrap(texels, textures[s.texture], lux_texture_slot_uv(s, uv0, uv1),
                                 LUX_SLOT_WRAP_S(s.flags), LUX_SLOT_WRAP_T(s.flags));
}

/* Normal maps (glTF 2.0 §3.9.3 "normalTexture"; material.normalTextureInfo
 * .scale, §5.22): a linear texel rgb in [0, 1] is the tangent-space vector
 * (2 rgb - 1) * (scale, scale, 1) in the frame (t, b, n): t the vertex
 * tangent Gram-Schmidt orthogonalised against n (interpolation tilts it),
 * b = cross(n, t) * sign(tangent.w) (§3.7.2.1 TANGENT), n the interpolated
 * vertex normal. The result is the unit shading normal.
 *
 * A map can tilt the normal below the geometric surface (strong maps,
 * grazing vertex normals). Such a normal is bent back toward ng until it is
 * LUX_NORMAL_MAP_MIN_COS above the tangent plane: the smallest change that
 * keeps every later step defined. Cycles' ensure_valid_reflection does the
 * same against the view direction; the texel point has none, so the bake
 * uses the geometric normal alone (docs/accuracy.md "Normal maps"). A frame
 * without a usable tangent or a zero map vector leaves n unchanged. */
#define LUX_NORMAL_MAP_MIN_COS 0.01f

inline float3 lux_normal_map_perturb(float3 n, float3 ng, float4 tangent, float3 rgb, float scale) {
  float3 t = tangent.xyz - n * dot(n, tangent.xyz);
  const float tl = length(t);
  if (!(tl > 1e-6f)) return n;
  t /= tl;
  const float3 b = cross(n, t) * (tangent.w < 0.0f ? -1.0f : 1.0f);
  const float3 m = (2.0f * rgb - 1.0f) * (float3)(scale, scale, 1.0f);
  float3 p = m.x * t + m.y * b + m.z * n;
  const float pl = length(p);
  if (!(pl > 1e-12f) || !isfinite(pl)) return n;
  p /= pl;
  const float d = dot(p, ng);
  if (d < LUX_NORMAL_MAP_MIN_COS) p = normalize(p + ng * (LUX_NORMAL_MAP_MIN_COS - d));
  return p;
}

#endif /* LUXEL_SHADING_TEXTURE_H */
