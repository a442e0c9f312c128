// BVH traversal on the CPU as XLA FFI handlers (radiometria.render, thesis ch. 8).
//
// The same queries as the lockstep JAX traversal in `_traversal.py`, one ray at a time in
// native code: XLA:CPU runs the JAX version as a while loop of many small kernels over a batch
// of lanes, whose per-iteration overhead and lockstep waste dominate on incoherent rays. The
// BVH layout is the one `build_bvh` writes (see `_bvh.py`): for each interior node the boxes
// of its two children `[lo0, hi0, lo1, hi1]` and two child codes (`c >= 0` interior node,
// `c == EMPTY` no child, otherwise a leaf `~(start << 3 | (count - 1))`).
//
// Arithmetic follows the JAX code operation for operation (compiled with -ffp-contract=off,
// so no fused multiply-adds): the watertight ray-triangle test of Woop, Benthin & Wald (2013,
// JCGT 2(1)) with each 2D edge function evaluated on its corners in a canonical order, so that
// shared edges give exactly opposite values and no ray leaks through a closed mesh; the
// robust slab test of Ize (2013), the far distance enlarged by 1 + 2 gamma_3; near child
// first; ties in t go to the lowest original face index; t_min < t < t_max exclusive.

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <thread>
#include <vector>

#include "xla/ffi/api/ffi.h"

namespace ffi = xla::ffi;

namespace {

constexpr int32_t kEmpty = std::numeric_limits<int32_t>::min();

template <typename T>
struct Ray {
  T o[3];
  T inv[3];  // 1 / direction, zero components replaced by +-tiny
  int kx, ky, kz;
  T sx, sy, sz;  // shear constants
  T ox, oy, oz;  // origin permuted to (kx, ky, kz)
  T t_lo, t_hi;
};

template <typename T>
inline Ray<T> setup_ray(const T* o, const T* d, T t_lo, T t_hi) {
  Ray<T> r;
  const T tiny = std::numeric_limits<T>::min();
  for (int i = 0; i < 3; ++i) {
    r.o[i] = o[i];
    T di = d[i];
    T ds = std::fabs(di) < tiny ? (di < 0 ? -tiny : tiny) : di;
    r.inv[i] = T(1) / ds;
  }
  const T ax = std::fabs(d[0]), ay = std::fabs(d[1]), az = std::fabs(d[2]);
  // kz: the axis of the largest |d| (first one on ties); kx = kz + 1, ky = kx + 1 (mod 3)
  r.kz = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
  r.kx = r.kz == 2 ? 0 : r.kz + 1;
  r.ky = r.kx == 2 ? 0 : r.kx + 1;
  const T dz = d[r.kz];
  r.sx = d[r.kx] / dz;
  r.sy = d[r.ky] / dz;
  r.sz = T(1) / dz;
  r.ox = o[r.kx];
  r.oy = o[r.ky];
  r.oz = o[r.kz];
  r.t_lo = t_lo;
  r.t_hi = t_hi;
  return r;
}

// p_x q_y - p_y q_x with the corners in lexicographic order: exactly antisymmetric.
template <typename T>
inline T edge(T px, T py, T qx, T qy) {
  const bool swap = (px > qx) || ((px == qx) && (py > qy));
  const T ax = swap ? qx : px, ay = swap ? qy : py;
  const T bx = swap ? px : qx, by = swap ? py : qy;
  const T e = ax * by - ay * bx;
  return swap ? -e : e;
}

// Watertight test; on a hit in (t_lo, t_hi) writes t and the barycentrics b1, b2.
template <typename T>
inline bool triangle_test(const Ray<T>& r, const T* v, T& t, T& b1, T& b2) {
  T cx[3], cy[3], cz[3];
  for (int c = 0; c < 3; ++c) {
    const T* p = v + 3 * c;
    const T px = p[r.kx] - r.ox;
    const T py = p[r.ky] - r.oy;
    const T pz = p[r.kz] - r.oz;
    cx[c] = px - r.sx * pz;
    cy[c] = py - r.sy * pz;
    cz[c] = r.sz * pz;
  }
  const T u = edge(cx[2], cy[2], cx[1], cy[1]);
  const T vv = edge(cx[0], cy[0], cx[2], cy[2]);
  const T w = edge(cx[1], cy[1], cx[0], cy[0]);
  const bool inside =
      (u >= 0 && vv >= 0 && w >= 0) || (u <= 0 && vv <= 0 && w <= 0);
  const T det = u + vv + w;
  if (!inside || det == 0) return false;
  const T inv_det = T(1) / det;
  const T ts = u * cz[0] + vv * cz[1] + w * cz[2];
  const T tt = ts * inv_det;
  if (!(tt > r.t_lo && tt < r.t_hi)) return false;
  t = tt;
  b1 = vv * inv_det;
  b2 = w * inv_det;
  return true;
}

template <typename T>
struct Tree {
  const T* boxes;          // (nodes, 12)
  const int32_t* children; // (nodes, 2)
  const T* tris;           // (f, 9)
  const int32_t* prims;    // (f,)
  int64_t stack_size;
  T grow;  // 1 + 2 gamma_3
};

// Robust slab test of one child box; returns whether it can hold a hit nearer than t_best.
template <typename T>
inline bool slab(const Ray<T>& r, const T* b, T t_best, T grow, T& near) {
  const T t0x = (b[0] - r.o[0]) * r.inv[0], t1x = (b[3] - r.o[0]) * r.inv[0];
  const T t0y = (b[1] - r.o[1]) * r.inv[1], t1y = (b[4] - r.o[1]) * r.inv[1];
  const T t0z = (b[2] - r.o[2]) * r.inv[2], t1z = (b[5] - r.o[2]) * r.inv[2];
  near = std::max(std::max(std::min(t0x, t1x), std::min(t0y, t1y)),
                  std::max(std::min(t0z, t1z), r.t_lo));
  const T far = std::min(std::min(std::max(t0x, t1x), std::max(t0y, t1y)),
                         std::max(t0z, t1z));
  return near <= std::min(far * grow, t_best);
}

// Traverses one ray. Closest hit: returns the face index (-1 on a miss) and writes t, b1, b2.
// Any hit: returns as soon as a triangle is hit.
template <typename T, bool kAny>
inline int32_t trace(const Tree<T>& tree, const Ray<T>& r, int32_t* stack, T& t_out,
                     T& b1_out, T& b2_out) {
  T t_best = r.t_hi;
  int32_t prim = -1;
  T b1_best = 0, b2_best = 0;
  if (!(r.t_hi > r.t_lo)) {  // an empty interval (an inactive ray): nothing to traverse
    t_out = std::numeric_limits<T>::infinity();
    b1_out = b2_out = T(0);
    return prim;
  }
  int64_t sp = 0;
  int32_t cur = 0;  // the root
  while (true) {
    if (cur >= 0) {
      const T* box = tree.boxes + 12 * static_cast<int64_t>(cur);
      const int32_t c0 = tree.children[2 * static_cast<int64_t>(cur)];
      const int32_t c1 = tree.children[2 * static_cast<int64_t>(cur) + 1];
      T n0, n1;
      const bool h0 = c0 != kEmpty && slab(r, box, t_best, tree.grow, n0);
      const bool h1 = c1 != kEmpty && slab(r, box + 6, t_best, tree.grow, n1);
      if (h0 && h1) {
        const bool second_first = n1 < n0;
        cur = second_first ? c1 : c0;
        if (sp < tree.stack_size) stack[sp++] = second_first ? c0 : c1;
        continue;
      }
      if (h0 || h1) {
        cur = h0 ? c0 : c1;
        continue;
      }
    } else if (cur != kEmpty) {  // a leaf: test its triangles
      const int32_t code = ~cur;
      const int64_t start = code >> 3;
      const int64_t end = start + (code & 7) + 1;
      for (int64_t k = start; k < end; ++k) {
        T t, b1, b2;
        if (!triangle_test(r, tree.tris + 9 * k, t, b1, b2)) continue;
        const int32_t pid = tree.prims[k];
        if (t < t_best || (t == t_best && pid < prim)) {
          t_best = t;
          prim = pid;
          b1_best = b1;
          b2_best = b2;
          if (kAny) {
            t_out = t_best;
            return prim;
          }
        }
      }
    }
    if (sp == 0) break;
    cur = stack[--sp];
  }
  t_out = prim >= 0 ? t_best : std::numeric_limits<T>::infinity();
  b1_out = b1_best;
  b2_out = b2_best;
  return prim;
}

template <typename T>
T gamma3() {
  const T eps = std::numeric_limits<T>::epsilon() * T(0.5);
  return T(3) * eps / (T(1) - T(3) * eps);
}

// Rays are split into chunks processed by the caller and by tasks on XLA's intra-op thread
// pool. The caller takes chunks itself until none is left and then waits only for chunks that
// a pool task has already claimed (and is running), so it never waits on a task that has not
// started: no deadlock when the pool's threads are busy elsewhere.
struct Chunks {
  std::atomic<int64_t> next{0};
  std::atomic<int64_t> done{0};
  int64_t count = 0;
};

template <typename F>
void parallel_chunks(ffi::ThreadPool& pool, int64_t n, int64_t chunk, int64_t threads,
                     F&& body) {
  const int64_t count = (n + chunk - 1) / chunk;
  if (count <= 1 || threads <= 1) {
    for (int64_t c = 0; c < count; ++c) body(c * chunk, std::min(n, (c + 1) * chunk));
    return;
  }
  auto state = std::make_shared<Chunks>();
  state->count = count;
  auto work = [state, n, chunk, body]() {
    int64_t c;
    while ((c = state->next.fetch_add(1)) < state->count) {
      body(c * chunk, std::min(n, (c + 1) * chunk));
      state->done.fetch_add(1);
    }
  };
  const int64_t helpers = std::min(threads, count) - 1;
  for (int64_t i = 0; i < helpers; ++i) pool.Schedule([work]() { work(); });
  work();
  while (state->done.load() < count) {
    std::this_thread::yield();
  }
}

// The ray buffers of a query: inputs o, d (n, 3), t_min, t_max (n,); outputs t, prim, b1, b2.
template <typename T>
struct RayIO {
  int64_t n;
  const T *o, *d, *lo, *hi;
  T* t;
  int32_t* prim;
  T *b1, *b2;
};

// Checks the ray buffers against one ray count and fills `io`; false on a size mismatch.
template <ffi::DataType DT>
bool ray_io(ffi::Buffer<DT> origins, ffi::Buffer<DT> directions, ffi::Buffer<DT> t_min,
            ffi::Buffer<DT> t_max, ffi::Result<ffi::Buffer<DT>>& t_out,
            ffi::Result<ffi::Buffer<ffi::S32>>& prim_out, ffi::Result<ffi::Buffer<DT>>& b1_out,
            ffi::Result<ffi::Buffer<DT>>& b2_out, RayIO<ffi::NativeType<DT>>& io) {
  const size_t n = t_min.element_count();
  if (origins.element_count() != 3 * n || directions.element_count() != 3 * n ||
      t_max.element_count() != n || t_out->element_count() != n ||
      prim_out->element_count() != n || b1_out->element_count() != n ||
      b2_out->element_count() != n) {
    return false;
  }
  io = {static_cast<int64_t>(n),  origins.typed_data(), directions.typed_data(),
        t_min.typed_data(),       t_max.typed_data(),   t_out->typed_data(),
        prim_out->typed_data(),   b1_out->typed_data(), b2_out->typed_data()};
  return true;
}

// Threads for one call: `threads`, or the size of XLA's intra-op pool when it is <= 0.
inline int64_t thread_count(ffi::ThreadPool& pool, int64_t threads) {
  return threads > 0 ? threads : std::max<int64_t>(1, pool.num_threads());
}

template <ffi::DataType DT, bool kAny>
ffi::Error query(ffi::ThreadPool pool, ffi::Buffer<DT> boxes, ffi::Buffer<ffi::S32> children,
                 ffi::Buffer<DT> tris, ffi::Buffer<ffi::S32> prims, ffi::Buffer<DT> origins,
                 ffi::Buffer<DT> directions, ffi::Buffer<DT> t_min, ffi::Buffer<DT> t_max,
                 int64_t stack_size, int64_t threads, ffi::Result<ffi::Buffer<DT>> t_out,
                 ffi::Result<ffi::Buffer<ffi::S32>> prim_out,
                 ffi::Result<ffi::Buffer<DT>> b1_out, ffi::Result<ffi::Buffer<DT>> b2_out) {
  using T = ffi::NativeType<DT>;
  RayIO<T> io;
  if (!ray_io<DT>(origins, directions, t_min, t_max, t_out, prim_out, b1_out, b2_out, io)) {
    return ffi::Error::InvalidArgument("radiometria BVH query: inconsistent ray buffer sizes");
  }
  if (boxes.element_count() != 6 * children.element_count() ||
      tris.element_count() != 9 * prims.element_count() || children.element_count() < 2) {
    return ffi::Error::InvalidArgument("radiometria BVH query: inconsistent BVH buffer sizes");
  }
  Tree<T> tree{boxes.typed_data(), children.typed_data(), tris.typed_data(),
               prims.typed_data(), std::max<int64_t>(stack_size, 1), T(1) + T(2) * gamma3<T>()};
  auto body = [&](int64_t begin, int64_t end) {
    std::vector<int32_t> stack(static_cast<size_t>(tree.stack_size));
    for (int64_t i = begin; i < end; ++i) {
      const Ray<T> r = setup_ray<T>(io.o + 3 * i, io.d + 3 * i, io.lo[i], io.hi[i]);
      T t = std::numeric_limits<T>::infinity(), b1 = 0, b2 = 0;
      int32_t p = trace<T, kAny>(tree, r, stack.data(), t, b1, b2);
      io.t[i] = p >= 0 ? t : std::numeric_limits<T>::infinity();
      io.prim[i] = p;
      io.b1[i] = p >= 0 && !kAny ? b1 : T(0);
      io.b2[i] = p >= 0 && !kAny ? b2 : T(0);
    }
  };
  parallel_chunks(pool, io.n, 4096, thread_count(pool, threads), body);
  return ffi::Error::Success();
}

// ---- brute force: every ray against every triangle, for scenes of a few dozen triangles -----
//
// The arithmetic of `_brute_loop` in `_traversal.py`: the corners of each triangle come sorted
// in one global (lexicographic) order, rows (9, f), so a shared edge is evaluated on the same
// operands in both triangles; a strict t < t_best keeps the lowest face index on ties. Rays
// go in blocks of kBlock, structure of arrays in L1, and the loop over the rays of a block is
// branch-free so that the compiler vectorises it (the triangles are the outer loop).

constexpr int kBlock = 256;  // rays per block
constexpr int kLanes = 16;   // each class is padded to a multiple of this (an AVX-512 register)
constexpr int kSlots = kBlock + 3 * kLanes;

// Per-block ray state, structure of arrays, the rays grouped by their axis kz; padding slots
// hold rays that never hit (t_lo = +inf) and are not written back (ray = -1).
template <typename T>
struct Block {
  alignas(64) T ox[kSlots], oy[kSlots], oz[kSlots], sx[kSlots], sy[kSlots], sz[kSlots];
  alignas(64) T tlo[kSlots], tbest[kSlots];
  alignas(64) int32_t best[kSlots];
  int32_t ray[kSlots];  // the ray of each slot (index in the block), -1 for padding
};

// One triangle against the slots [begin, end) of a block, whose rays all have the axis KZ (so
// the permutation to (kx, ky, kz) is known at compile time and the loop vectorises).
template <typename T, bool kAny, int KZ>
inline void brute_class(const T* q, int32_t kk, Block<T>& b, int begin, int end) {
  constexpr int KX = KZ == 2 ? 0 : KZ + 1;
  constexpr int KY = KX == 2 ? 0 : KX + 1;
  const T ax0 = q[KX], ay0 = q[KY], az0 = q[KZ];
  const T bx0 = q[3 + KX], by0 = q[3 + KY], bz0 = q[3 + KZ];
  const T cx0 = q[6 + KX], cy0 = q[6 + KY], cz0 = q[6 + KZ];
#pragma GCC ivdep
  for (int i = begin; i < end; ++i) {
    const T apz = az0 - b.oz[i], bpz = bz0 - b.oz[i], cpz = cz0 - b.oz[i];
    const T ax = (ax0 - b.ox[i]) - b.sx[i] * apz;
    const T ay = (ay0 - b.oy[i]) - b.sy[i] * apz;
    const T bx = (bx0 - b.ox[i]) - b.sx[i] * bpz;
    const T by = (by0 - b.oy[i]) - b.sy[i] * bpz;
    const T cx = (cx0 - b.ox[i]) - b.sx[i] * cpz;
    const T cy = (cy0 - b.oy[i]) - b.sy[i] * cpz;
    const T az = b.sz[i] * apz, bz = b.sz[i] * bpz, cz = b.sz[i] * cpz;
    const T e_ab = ax * by - ay * bx;
    const T e_bc = bx * cy - by * cx;
    const T e_ac = ax * cy - ay * cx;
    const T u = -e_bc, v = e_ac, w = -e_ab;
    const bool inside = ((u >= 0) & (v >= 0) & (w >= 0)) | ((u <= 0) & (v <= 0) & (w <= 0));
    const T det = u + v + w;
    const T t = (u * az + v * bz + w * cz) / (det != 0 ? det : T(1));
    const bool hit = inside & (det != 0) & (t > b.tlo[i]) & (t < b.tbest[i]);
    if (!kAny) b.tbest[i] = hit ? t : b.tbest[i];
    b.best[i] = hit ? kk : b.best[i];
  }
}

// The barycentrics of each slot's hit in [begin, end) of one axis class, as `_brute_closest`
// recomputes them (no range checks; `edge` and the triangle test's operations, branch-free, so
// that the loop vectorises with gathers of the hit triangles' corners); no hit gets 0.
template <typename T, int KZ>
inline void brute_barycentrics(const T* tri, Block<T>& b, T* b1, T* b2, int begin, int end) {
  constexpr int KX = KZ == 2 ? 0 : KZ + 1;
  constexpr int KY = KX == 2 ? 0 : KX + 1;
#pragma GCC ivdep
  for (int i = begin; i < end; ++i) {
    const int32_t p = b.best[i];
    const int64_t at = 9 * static_cast<int64_t>(p >= 0 ? p : 0);
    T cx[3], cy[3];
    for (int c = 0; c < 3; ++c) {
      const T pz = tri[at + 3 * c + KZ] - b.oz[i];
      cx[c] = (tri[at + 3 * c + KX] - b.ox[i]) - b.sx[i] * pz;
      cy[c] = (tri[at + 3 * c + KY] - b.oy[i]) - b.sy[i] * pz;
    }
    const T u = edge(cx[2], cy[2], cx[1], cy[1]);
    const T vv = edge(cx[0], cy[0], cx[2], cy[2]);
    const T w = edge(cx[1], cy[1], cx[0], cy[0]);
    const T det = u + vv + w;
    const bool ok = (((u >= 0) & (vv >= 0) & (w >= 0)) | ((u <= 0) & (vv <= 0) & (w <= 0))) &
                    (det != 0);
    const T inv_det = T(1) / (ok ? det : T(1));
    b1[i] = p >= 0 ? vv * inv_det : T(0);
    b2[i] = p >= 0 ? w * inv_det : T(0);
  }
}

template <typename T, bool kAny>
void brute_block(const T* rows, int64_t f, const T* tri, const RayIO<T>& io, int64_t begin,
                 int64_t end) {
  const T *o = io.o, *d = io.d, *lo = io.lo, *hi = io.hi;
  Block<T> b;
  // Per ray of the block, what `setup_ray` computes for the triangle test (its axis kz, the
  // shear constants, the permuted origin; not the inverse direction), in a loop that vectorises.
  alignas(64) T rox[kBlock], roy[kBlock], roz[kBlock], rsx[kBlock], rsy[kBlock], rsz[kBlock];
  alignas(64) int32_t rkz[kBlock];
  alignas(64) T sb1[kSlots], sb2[kSlots];
  for (int64_t base = begin; base < end; base += kBlock) {
    const int m = static_cast<int>(std::min<int64_t>(kBlock, end - base));
    const T* ob = o + 3 * base;
    const T* db = d + 3 * base;
#pragma GCC ivdep
    for (int i = 0; i < m; ++i) {
      const T dx = db[3 * i], dy = db[3 * i + 1], dz = db[3 * i + 2];
      const T ox = ob[3 * i], oy = ob[3 * i + 1], oz = ob[3 * i + 2];
      const T ax = std::fabs(dx), ay = std::fabs(dy), az = std::fabs(dz);
      const bool z0 = (ax >= ay) & (ax >= az);
      const bool z1 = !z0 & (ay >= az);
      // (kx, ky, kz) = (1, 2, 0), (2, 0, 1) or (0, 1, 2)
      const T dkz = z0 ? dx : (z1 ? dy : dz);
      const T dkx = z0 ? dy : (z1 ? dz : dx);
      const T dky = z0 ? dz : (z1 ? dx : dy);
      rsx[i] = dkx / dkz;
      rsy[i] = dky / dkz;
      rsz[i] = T(1) / dkz;
      roz[i] = z0 ? ox : (z1 ? oy : oz);
      rox[i] = z0 ? oy : (z1 ? oz : ox);
      roy[i] = z0 ? oz : (z1 ? ox : oy);
      rkz[i] = z0 ? 0 : (z1 ? 1 : 2);
    }
    // group the block's rays by kz: slots [0, e0) kz = 0, [e0, e1) kz = 1, [e1, e2) kz = 2
    int count[3] = {0, 0, 0};
    for (int i = 0; i < m; ++i) ++count[rkz[i]];
    auto padded = [](int c) { return (c + kLanes - 1) / kLanes * kLanes; };
    const int e0 = padded(count[0]), e1 = e0 + padded(count[1]), e2 = e1 + padded(count[2]);
    for (int s = 0; s < e2; ++s) {  // padding: rays that never hit
      b.ox[s] = b.oy[s] = b.oz[s] = b.sx[s] = b.sy[s] = b.sz[s] = T(0);
      b.tlo[s] = std::numeric_limits<T>::infinity();
      b.tbest[s] = T(0);
      b.best[s] = -1;
      b.ray[s] = -1;
    }
    int next[3] = {0, e0, e1};
    for (int i = 0; i < m; ++i) {
      const int s = next[rkz[i]]++;
      b.ox[s] = rox[i], b.oy[s] = roy[i], b.oz[s] = roz[i];
      b.sx[s] = rsx[i], b.sy[s] = rsy[i], b.sz[s] = rsz[i];
      b.tlo[s] = lo[base + i], b.tbest[s] = hi[base + i];
      b.ray[s] = i;
    }
    for (int64_t k = 0; k < f; ++k) {
      T q[9];
      for (int j = 0; j < 9; ++j) q[j] = rows[j * f + k];
      const int32_t kk = static_cast<int32_t>(k);
      brute_class<T, kAny, 0>(q, kk, b, 0, e0);
      brute_class<T, kAny, 1>(q, kk, b, e0, e1);
      brute_class<T, kAny, 2>(q, kk, b, e1, e2);
    }
    if (!kAny && f > 0) {  // (no triangles: no hits, and no corners to gather)
      brute_barycentrics<T, 0>(tri, b, sb1, sb2, 0, e0);
      brute_barycentrics<T, 1>(tri, b, sb1, sb2, e0, e1);
      brute_barycentrics<T, 2>(tri, b, sb1, sb2, e1, e2);
    } else {
      std::fill(sb1, sb1 + e2, T(0));
      std::fill(sb2, sb2 + e2, T(0));
    }
    for (int s = 0; s < e2; ++s) {
      if (b.ray[s] < 0) continue;
      const int64_t g = base + b.ray[s];
      const int32_t p = b.best[s];
      io.prim[g] = p;
      io.t[g] = (p >= 0 && !kAny) ? b.tbest[s] : std::numeric_limits<T>::infinity();
      io.b1[g] = sb1[s];  // zero for any-hit queries and misses
      io.b2[g] = sb2[s];
    }
  }
}

template <ffi::DataType DT, bool kAny>
ffi::Error brute(ffi::ThreadPool pool, ffi::Buffer<DT> rows, ffi::Buffer<DT> tris,
                 ffi::Buffer<DT> origins, ffi::Buffer<DT> directions, ffi::Buffer<DT> t_min,
                 ffi::Buffer<DT> t_max, int64_t threads, ffi::Result<ffi::Buffer<DT>> t_out,
                 ffi::Result<ffi::Buffer<ffi::S32>> prim_out,
                 ffi::Result<ffi::Buffer<DT>> b1_out, ffi::Result<ffi::Buffer<DT>> b2_out) {
  using T = ffi::NativeType<DT>;
  const int64_t f = static_cast<int64_t>(tris.element_count() / 9);
  RayIO<T> io;
  if (!ray_io<DT>(origins, directions, t_min, t_max, t_out, prim_out, b1_out, b2_out, io)) {
    return ffi::Error::InvalidArgument("radiometria brute force: inconsistent ray buffer sizes");
  }
  if (rows.element_count() != tris.element_count() || tris.element_count() != size_t(9 * f)) {
    return ffi::Error::InvalidArgument("radiometria brute force: inconsistent triangle buffers");
  }
  const T* r = rows.typed_data();
  const T* tr = tris.typed_data();
  auto body = [&](int64_t begin, int64_t end) {
    brute_block<T, kAny>(r, f, tr, io, begin, end);
  };
  parallel_chunks(pool, io.n, 4096, thread_count(pool, threads), body);
  return ffi::Error::Success();
}

template <ffi::DataType DT>
constexpr auto bind_brute() {
  return ffi::Ffi::Bind()
      .Ctx<ffi::ThreadPool>()
      .template Arg<ffi::Buffer<DT>>()
      .template Arg<ffi::Buffer<DT>>()
      .template Arg<ffi::Buffer<DT>>()
      .template Arg<ffi::Buffer<DT>>()
      .template Arg<ffi::Buffer<DT>>()
      .template Arg<ffi::Buffer<DT>>()
      .template Attr<int64_t>("threads")
      .template Ret<ffi::Buffer<DT>>()
      .template Ret<ffi::Buffer<ffi::S32>>()
      .template Ret<ffi::Buffer<DT>>()
      .template Ret<ffi::Buffer<DT>>();
}

template <ffi::DataType DT, bool kAny>
constexpr auto bind() {
  return ffi::Ffi::Bind()
      .Ctx<ffi::ThreadPool>()
      .template Arg<ffi::Buffer<DT>>()
      .template Arg<ffi::Buffer<ffi::S32>>()
      .template Arg<ffi::Buffer<DT>>()
      .template Arg<ffi::Buffer<ffi::S32>>()
      .template Arg<ffi::Buffer<DT>>()
      .template Arg<ffi::Buffer<DT>>()
      .template Arg<ffi::Buffer<DT>>()
      .template Arg<ffi::Buffer<DT>>()
      .template Attr<int64_t>("stack_size")
      .template Attr<int64_t>("threads")
      .template Ret<ffi::Buffer<DT>>()
      .template Ret<ffi::Buffer<ffi::S32>>()
      .template Ret<ffi::Buffer<DT>>()
      .template Ret<ffi::Buffer<DT>>();
}

}  // namespace

// The float32 and float64 handlers are compiled as two libraries, each when first needed
// (-DRADIOMETRIA_PART=32 and =64: `radiometria._native_build.build`); without the macro this
// one file defines all eight.
#if !defined(RADIOMETRIA_PART) || RADIOMETRIA_PART == 32
XLA_FFI_DEFINE_HANDLER_SYMBOL(RadiometriaBvhClosestF32, (query<ffi::F32, false>),
                              (bind<ffi::F32, false>()));
XLA_FFI_DEFINE_HANDLER_SYMBOL(RadiometriaBvhAnyF32, (query<ffi::F32, true>),
                              (bind<ffi::F32, true>()));
XLA_FFI_DEFINE_HANDLER_SYMBOL(RadiometriaBruteClosestF32, (brute<ffi::F32, false>),
                              (bind_brute<ffi::F32>()));
XLA_FFI_DEFINE_HANDLER_SYMBOL(RadiometriaBruteAnyF32, (brute<ffi::F32, true>),
                              (bind_brute<ffi::F32>()));
#endif
#if !defined(RADIOMETRIA_PART) || RADIOMETRIA_PART == 64
XLA_FFI_DEFINE_HANDLER_SYMBOL(RadiometriaBvhClosestF64, (query<ffi::F64, false>),
                              (bind<ffi::F64, false>()));
XLA_FFI_DEFINE_HANDLER_SYMBOL(RadiometriaBvhAnyF64, (query<ffi::F64, true>),
                              (bind<ffi::F64, true>()));
XLA_FFI_DEFINE_HANDLER_SYMBOL(RadiometriaBruteClosestF64, (brute<ffi::F64, false>),
                              (bind_brute<ffi::F64>()));
XLA_FFI_DEFINE_HANDLER_SYMBOL(RadiometriaBruteAnyF64, (brute<ffi::F64, true>),
                              (bind_brute<ffi::F64>()));
#endif
