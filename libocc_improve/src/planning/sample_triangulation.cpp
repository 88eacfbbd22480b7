#include "occ_improve/planning/sample_triangulation.hpp"
#include "planning/checked_triangulation.hpp"

#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/maps/column_map.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>
#include <string>
#include <utility>

namespace occ_improve {

void TriangulationParams::validate() const {
  detail::require_parameter(discontinuity_sigmas > 0, "discontinuity_sigmas", discontinuity_sigmas, "> 0");
  detail::require_parameter(max_edge_columns >= 1, "max_edge_columns", max_edge_columns, ">= 1");
}

namespace {

__extension__ typedef __int128 Int128;  // exact in-circle tests with a super corner 2^22 px away

constexpr std::int64_t kSuper = std::int64_t{1} << 22;  // super triangle corners: far outside any image
constexpr int kMaxSide = 1 << 20;                       // images up to this size lie well inside it
constexpr int kSmallSide = 1 << 13;                     // below it the in-circle test fits in 64 bits

struct Point {
  std::int64_t x, y;
};

std::int64_t orient(const Point& a, const Point& b, const Point& c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

/// The order of the symbolic perturbation below: a strict total order on distinct points.
bool ranks_before(const Point& p, const Point& q) { return p.y != q.y ? p.y < q.y : p.x < q.x; }

/// in_circle's tie (D = 0), by the symbolic perturbation in_circle's comment describes; out of line, so
/// that the determinant, which decides all but a few tests, inlines where the triangulation tests circles.
[[gnu::noinline]] bool in_circle_tie(const Point& a, const Point& b, const Point& c, const Point& d) {
  std::array<std::pair<const Point*, std::int64_t>, 4> cofactor{
      {{&a, orient(b, c, d)}, {&b, -orient(a, c, d)}, {&c, orient(a, b, d)}, {&d, -orient(a, b, c)}}};
  std::sort(cofactor.begin(), cofactor.end(), [](const auto& p, const auto& q) { return ranks_before(*q.first, *p.first); });
  for (const auto& [point, value] : cofactor)
    if (value != 0) return value > 0;
  return false;  // unreachable: orient(a, b, c) > 0
}

/// Whether d lies inside the circle through a, b, c (orient(a, b, c) > 0), with co-circular points
/// decided by a symbolic perturbation (simulation of simplicity): each point's lift x^2 + y^2 is raised
/// by an infinitesimal, larger for a point that ranks later. The determinant D of rows (x, y, x^2 + y^2, 1)
/// for a, b, c, d is linear in each lift, with cofactors orient(b, c, d), -orient(a, c, d), orient(a, b, d)
/// and -orient(a, b, c); where D = 0 its sign is that of the cofactor of the latest-ranked point among
/// those whose cofactor is not 0 (d's never is). Every tie is thereby decided the same way whatever the
/// insertion order, so the triangulation of a set of samples is one and the same (SampleTriangulator
/// inserting shot after shot gives triangulate_samples' triangles) instead of depending on which of
/// the co-circular samples came first (on a pixel grid, most ties are such squares and rectangles).
template <class T>
bool in_circle(const Point& a, const Point& b, const Point& c, const Point& d) {
  const T adx = a.x - d.x, ady = a.y - d.y, bdx = b.x - d.x, bdy = b.y - d.y, cdx = c.x - d.x, cdy = c.y - d.y;
  const T ad = adx * adx + ady * ady, bd = bdx * bdx + bdy * bdy, cd = cdx * cdx + cdy * cdy;
  const T det = adx * (bdy * cd - bd * cdy) - ady * (bdx * cd - bd * cdx) + ad * (bdx * cdy - bdy * cdx);
  if (det != 0) return det > 0;
  return in_circle_tie(a, b, c, d);
}

/// Position of (x, y) along a Hilbert curve over a side x side square (side a power of two).
std::uint64_t hilbert_index(std::uint32_t side, std::uint32_t x, std::uint32_t y) {
  std::uint64_t d = 0;
  for (std::uint32_t s = side / 2; s > 0; s /= 2) {
    const std::uint32_t rx = (x & s) ? 1u : 0u, ry = (y & s) ? 1u : 0u;
    d += static_cast<std::uint64_t>(s) * s * ((3u * rx) ^ ry);
    // The quadrant's rotation by masks (the compiler branched on selects; the samples come in no order along
    // the curve): side - 1 - x is x ^ (side - 1) for x < side, and an xor swaps x and y (flipping both keeps
    // x ^ y).
    const std::uint32_t flip = (0u - (rx & (ry ^ 1u))) & (side - 1), swap = (0u - (ry ^ 1u)) & (x ^ y);
    x ^= flip ^ swap;
    y ^= flip ^ swap;
  }
  return d;
}

struct Triangle {
  std::array<std::int32_t, 3> v;  // counter-clockwise (orient > 0)
  std::array<std::int32_t, 3> n;  // n[i]: neighbour across the edge opposite v[i], -1 outside the super triangle
};

/// Room for `size` elements; growing, at least double (an update that adds a shot's samples must not
/// copy every vertex and triangle each time).
template <class T>
void reserve_geometric(std::vector<T>& v, std::size_t size) {
  if (size > v.capacity()) v.reserve(std::max(size, 2 * v.capacity()));
}

/// Bowyer-Watson over integer points, which may be added at any time: points 0, 1, 2 are the super
/// triangle's corners, point kCorners + v is vertex v.
class Delaunay {
public:
  static constexpr std::int32_t kCorners = 3;
  /// Links longer than this are not re-triangulated by remove() (a hull vertex of a fan can have
  /// thousands of neighbours; a sample on the image typically has 6).
  static constexpr std::size_t kMaxLinkForRemoval = 256;

  explicit Delaunay(bool small) : small_(small) {
    points_ = {{-kSuper, -kSuper}, {kSuper, -kSuper}, {0, kSuper}};  // counter-clockwise
    tris_.push_back({{0, 1, 2}, {-1, -1, -1}});
    mark_.push_back(0);
    first_of_.assign(points_.size(), -1);
  }

  void reserve(std::size_t vertices) {
    reserve_geometric(points_, vertices + kCorners);
    reserve_geometric(first_of_, vertices + kCorners);
    reserve_geometric(tris_, 2 * vertices + 1);  // 2 n + 1 triangles in the end
    reserve_geometric(mark_, 2 * vertices + 1);
  }

  /// Adds the next vertex at p, not yet inserted.
  void add(const Point& p) {
    points_.push_back(p);
    first_of_.push_back(-1);
  }
  /// Inserts vertex `vertex`, its walk starting beside `near_vertex` (an inserted vertex a few pixels away:
  /// a walk of a few steps), or from the last new triangle when that is -1. Where the walk starts changes
  /// which slots the new triangles take, not the triangulation.
  void insert(std::int32_t vertex, std::int32_t near_vertex) {
    const std::int32_t i = vertex + kCorners;
    dig_cavity(locate(pt(i), near_vertex >= 0 ? first_of_[static_cast<std::size_t>(near_vertex + kCorners)] : last_), i);
    fill_cavity(i);
  }
  bool inserted(std::int32_t vertex) const { return first_of_[static_cast<std::size_t>(vertex + kCorners)] >= 0; }

  /// Removes vertex `vertex` (it must have been inserted; false, and the structure unusable, if no ear is
  /// found, which cannot happen for a Delaunay star): its star gives way to the Delaunay triangulation
  /// of its link, built ear by ear (a convex corner of the link whose circumcircle holds no other link
  /// vertex, by the same tie rule), so the result is the triangulation of the remaining points whatever
  /// the order of removals and insertions. Its point stays, referenced by no triangle (compact drops it).
  bool remove(std::int32_t vertex) {
    const std::int32_t i = vertex + kCorners, first = first_of_[static_cast<std::size_t>(i)];
    // The star (i, link[j], link[j + 1]) counter-clockwise, and who lies across each link edge: the outer
    // triangle and its slot that points back into the star (none beyond the super triangle).
    star_.clear();
    link_.clear();
    owner_.clear();
    std::int32_t t = first;
    do {
      const Triangle& T = tris_[static_cast<std::size_t>(t)];
      const auto k = static_cast<std::size_t>((T.v[1] == i) + 2 * (T.v[2] == i));
      star_.push_back(t);
      link_.push_back(T.v[kNext[k]]);
      const std::int32_t outer = T.n[k];
      owner_.push_back({outer, outer < 0 ? -1 : slot_of_neighbour(outer, t)});
      t = T.n[kNext[k]];
    } while (t != first);
    if (link_.size() > kMaxLinkForRemoval) return false;  // the ear search is quadratic in the link
    // Ears: position j of the link (a circular list) becomes triangle (link[prev], link[j], link[next]);
    // the new edge (prev, next) takes the place of the two edges it closes, owned by the new triangle.
    const auto m = static_cast<std::int32_t>(link_.size());
    std::vector<std::int32_t> next(static_cast<std::size_t>(m)), prev(static_cast<std::size_t>(m));
    for (std::int32_t j = 0; j < m; ++j) {
      next[static_cast<std::size_t>(j)] = (j + 1) % m;
      prev[static_cast<std::size_t>(j)] = (j + m - 1) % m;
    }
    std::size_t reused = 0;
    std::int32_t j = 0;
    for (std::int32_t left = m; left >= 3; --left) {
      for (std::int32_t tried = 0; left > 3 && !is_ear(prev[static_cast<std::size_t>(j)], j, next[static_cast<std::size_t>(j)], next);
           j = next[static_cast<std::size_t>(j)])
        if (++tried > left) return false;  // never for a Delaunay star; the caller starts over
      const std::int32_t p = prev[static_cast<std::size_t>(j)], q = next[static_cast<std::size_t>(j)];
      const std::int32_t nt = star_[reused++];
      Triangle& N = tris_[static_cast<std::size_t>(nt)];
      N.v = {link_[static_cast<std::size_t>(p)], link_[static_cast<std::size_t>(j)], link_[static_cast<std::size_t>(q)]};
      join(nt, 0, owner_[static_cast<std::size_t>(j)]);  // across (link[j], link[q])
      join(nt, 2, owner_[static_cast<std::size_t>(p)]);  // across (link[p], link[j])
      if (left == 3) {
        join(nt, 1, owner_[static_cast<std::size_t>(q)]);  // the last triangle closes (link[q], link[p])
      } else {
        owner_[static_cast<std::size_t>(p)] = {nt, 1};  // the edge (link[p], link[q]), across from link[j]
        next[static_cast<std::size_t>(p)] = q;
        prev[static_cast<std::size_t>(q)] = p;
      }
      for (const std::int32_t v : N.v) {
        first_of_[static_cast<std::size_t>(v)] = nt;
        if (track_touched_ && v >= kCorners) touched_.push_back(v - kCorners);
      }
      last_ = nt;
      j = q;
    }
    for (; reused < star_.size(); ++reused) mark_[static_cast<std::size_t>(star_[reused])] = kDead;
    first_of_[static_cast<std::size_t>(i)] = -1;
    return true;
  }

  /// Drops the points of removed vertices: vertex v becomes renumbered[v] (-1: removed, else increasing).
  void compact(const std::vector<std::int32_t>& renumbered) {
    const auto point = [&](std::int32_t p) { return p < kCorners ? p : renumbered[static_cast<std::size_t>(p - kCorners)] + kCorners; };
    for (std::size_t t = 0; t < tris_.size(); ++t)
      if (mark_[t] != kDead)
        for (std::int32_t& v : tris_[t].v) v = point(v);
    std::size_t kept = kCorners;
    for (std::size_t v = 0; v < renumbered.size(); ++v)
      if (renumbered[v] >= 0) {
        points_[kept] = points_[v + kCorners];
        first_of_[kept++] = first_of_[v + kCorners];
      }
    points_.resize(kept);
    first_of_.resize(kept);
    std::vector<std::int32_t> touched;
    for (const std::int32_t v : touched_)
      if (renumbered[static_cast<std::size_t>(v)] >= 0) touched.push_back(renumbered[static_cast<std::size_t>(v)]);
    touched_.swap(touched);
  }

  /// Calls visit(j) for the other two vertices of every triangle without a super corner around `vertex`
  /// (each neighbour twice for an interior vertex: the entries measure_non_planarity gathers).
  template <class Visit>
  void for_each_neighbour_entry(std::int32_t vertex, Visit&& visit) const {
    const std::int32_t i = vertex + kCorners, first = first_of_[static_cast<std::size_t>(i)];
    std::int32_t t = first;
    do {  // around i: the super triangle encloses every vertex, so its star is a closed fan
      const Triangle& T = tris_[static_cast<std::size_t>(t)];
      const auto k = static_cast<std::size_t>((T.v[1] == i) + 2 * (T.v[2] == i));
      const std::int32_t a = T.v[kNext[k]], b = T.v[kPrev[k]];
      if (a >= kCorners && b >= kCorners) {
        visit(a - kCorners);
        visit(b - kCorners);
      }
      t = T.n[kNext[k]];  // across the edge (v[k + 2], i)
    } while (t != first);
  }

  /// From now on, record the vertices whose neighbours change (take_touched), for an update that
  /// remeasures only those.
  void track_touched(bool on) { track_touched_ = on; }

  /// Vertices whose neighbours changed since the last call (the cavities' boundaries), with repeats.
  std::vector<std::int32_t> take_touched() {
    std::vector<std::int32_t> out;
    out.swap(touched_);
    return out;
  }

  /// The triangles without a super corner, as vertex indices.
  void vertex_triangles(std::vector<std::array<std::int32_t, 3>>& out) const {
    out.clear();
    for (std::size_t t = 0; t < tris_.size(); ++t) {
      const auto& v = tris_[t].v;
      if (mark_[t] != kDead && v[0] >= kCorners && v[1] >= kCorners && v[2] >= kCorners)
        out.push_back({v[0] - kCorners, v[1] - kCorners, v[2] - kCorners});
    }
  }

private:
  static constexpr std::int64_t kDead = std::numeric_limits<std::int64_t>::min();  // never a stamp
  static constexpr std::array<int, 3> kNext{1, 2, 0}, kPrev{2, 0, 1};  // (i + 1) % 3, (i + 2) % 3
  struct Edge {
    std::int32_t a, b, outer;
  };

  struct Owner {
    std::int32_t triangle, slot;  ///< the triangle across an edge and its slot that points back; -1: none
  };
  std::int32_t slot_of_neighbour(std::int32_t t, std::int32_t neighbour) const {
    const Triangle& T = tris_[static_cast<std::size_t>(t)];
    return (T.n[1] == neighbour) + 2 * (T.n[2] == neighbour);
  }
  void join(std::int32_t t, int slot, const Owner& o) {
    tris_[static_cast<std::size_t>(t)].n[static_cast<std::size_t>(slot)] = o.triangle;
    if (o.triangle >= 0) tris_[static_cast<std::size_t>(o.triangle)].n[static_cast<std::size_t>(o.slot)] = t;
  }
  /// Whether link position j, between p and q, is an ear: a convex corner whose circumcircle holds no other
  /// vertex of the link still open (`next` runs around it).
  bool is_ear(std::int32_t p, std::int32_t j, std::int32_t q, const std::vector<std::int32_t>& next) const {
    const std::int32_t a = link_[static_cast<std::size_t>(p)], b = link_[static_cast<std::size_t>(j)], c = link_[static_cast<std::size_t>(q)];
    if (orient(pt(a), pt(b), pt(c)) <= 0) return false;
    for (std::int32_t r = next[static_cast<std::size_t>(q)]; r != p; r = next[static_cast<std::size_t>(r)]) {
      const std::int32_t d = link_[static_cast<std::size_t>(r)];
      const bool small = small_ && std::min({a, b, c, d}) >= kCorners;
      if (small ? in_circle<std::int64_t>(pt(a), pt(b), pt(c), pt(d)) : in_circle<Int128>(pt(a), pt(b), pt(c), pt(d))) return false;
    }
    return true;
  }

  bool inside_circle(std::int32_t t, const Point& d) const {
    const Triangle& T = tris_[static_cast<std::size_t>(t)];
    const Point &a = pt(T.v[0]), &b = pt(T.v[1]), &c = pt(T.v[2]);
    if (small_ && T.v[0] >= kCorners && T.v[1] >= kCorners && T.v[2] >= kCorners) return in_circle<std::int64_t>(a, b, c, d);
    return in_circle<Int128>(a, b, c, d);
  }
  const Point& pt(std::int32_t i) const { return points_[static_cast<std::size_t>(i)]; }

  /// Visibility walk from triangle `t`; in a Delaunay triangulation it cannot cycle. The edge tried first
  /// rotates so that the walk does not favour one direction.
  std::int32_t locate(const Point& p, std::int32_t t) {
    for (unsigned step = 0;; ++step) {
      const Triangle& T = tris_[static_cast<std::size_t>(t)];
      bool moved = false;
      for (unsigned k = 0; k < 3 && !moved; ++k) {
        const unsigned i = (k + step) % 3;
        if (orient(pt(T.v[kNext[i]]), pt(T.v[kPrev[i]]), p) < 0) {
          t = T.n[i];
          moved = true;
        }
      }
      if (!moved) return t;
    }
  }

  /// The triangles whose circumcircle holds p strictly (connected, from the one containing p), and the
  /// edges that bound them.
  void dig_cavity(std::int32_t start, std::int32_t p) {
    ++stamp_;  // mark_: stamp_ in the cavity, -stamp_ found outside it (a triangle beside two cavity edges)
    const Point& q = pt(p);
    bad_.clear();
    boundary_.clear();
    stack_.assign(1, start);
    mark_[static_cast<std::size_t>(start)] = stamp_;
    while (!stack_.empty()) {
      const std::int32_t u = stack_.back();
      stack_.pop_back();
      bad_.push_back(u);
      for (int i = 0; i < 3; ++i) {
        const Triangle& U = tris_[static_cast<std::size_t>(u)];
        const std::int32_t nb = U.n[i];
        if (nb >= 0) {
          std::int64_t& mark = mark_[static_cast<std::size_t>(nb)];
          if (mark == stamp_) continue;  // inside the cavity
          if (mark != -stamp_ && inside_circle(nb, q)) {
            mark = stamp_;
            stack_.push_back(nb);
            continue;
          }
          mark = -stamp_;
        }
        boundary_.push_back({U.v[kNext[i]], U.v[kPrev[i]], nb});
      }
    }
  }

  /// One triangle (p, a, b) per boundary edge, in the cavity's slots first.
  void fill_cavity(std::int32_t p) {
    new_.clear();
    for (std::size_t k = 0; k < boundary_.size(); ++k) {
      std::int32_t t;
      if (k < bad_.size()) {
        t = bad_[k];
      } else {
        t = static_cast<std::int32_t>(tris_.size());
        tris_.push_back({});
        mark_.push_back(0);
      }
      const Edge& e = boundary_[k];
      tris_[static_cast<std::size_t>(t)] = {{p, e.a, e.b}, {e.outer, -1, -1}};
      if (e.outer >= 0) {
        // By the edge's vertices, not by the old neighbour's index: that slot may already hold a new triangle.
        // The outer triangle runs the edge as (b, a), so the slot opposite it follows a's (no branch).
        Triangle& O = tris_[static_cast<std::size_t>(e.outer)];
        const int a_slot = (O.v[1] == e.a) + 2 * (O.v[2] == e.a);
        O.n[static_cast<std::size_t>(kNext[static_cast<std::size_t>(a_slot)])] = t;
      }
      first_of_[static_cast<std::size_t>(e.a)] = t;
      if (track_touched_ && e.a >= kCorners) touched_.push_back(e.a - kCorners);
      new_.push_back(t);
    }
    // (p, a, b) meets (p, b, c) across the edge (b, p): opposite a in the first, opposite c in the second.
    for (const std::int32_t t : new_) {
      Triangle& T = tris_[static_cast<std::size_t>(t)];
      T.n[1] = first_of_[static_cast<std::size_t>(T.v[2])];
      tris_[static_cast<std::size_t>(T.n[1])].n[2] = t;
    }
    for (std::size_t k = boundary_.size(); k < bad_.size(); ++k) mark_[static_cast<std::size_t>(bad_[k])] = kDead;
    last_ = first_of_[static_cast<std::size_t>(p)] = new_.front();
  }

  std::vector<Point> points_;
  bool small_, track_touched_ = false;
  std::vector<Triangle> tris_;
  std::vector<std::int64_t> mark_;  // stamp of the cavity a triangle was last found in; kDead: unused slot
  std::vector<std::int32_t> first_of_;
  std::vector<std::int32_t> bad_, stack_, new_, touched_, star_, link_;
  std::vector<Owner> owner_;
  std::vector<Edge> boundary_;
  std::int64_t stamp_ = 0;
  std::int32_t last_ = 0;
};

/// Vertices [first, vertex_count()) in Hilbert-curve order of their pixels: a least-significant-digit radix
/// sort of their positions along the curve (distinct, one sample per pixel: the order std::sort gave on
/// (position, index) keys), two passes over the vertices at 640 x 480.
std::vector<std::int32_t> insertion_order(const SampleTriangulation& s, std::size_t first) {
  std::uint32_t side = 1;
  int position_bits = 0;
  while (side < static_cast<std::uint32_t>(std::max(s.width, s.height))) {
    side *= 2;
    position_bits += 2;
  }
  const std::size_t n = s.vertex_count() - first;
  std::vector<std::uint64_t> position(n);
  std::vector<std::int32_t> order(n), sorted(n);
  for (std::size_t k = 0; k < n; ++k) {
    const auto i = static_cast<std::int32_t>(first + k);
    position[k] = hilbert_index(side, static_cast<std::uint32_t>(s.x(i)), static_cast<std::uint32_t>(s.y(i)));
    order[k] = i;
  }
  constexpr int kDigitBits = 11;
  for (int shift = 0; shift < position_bits; shift += kDigitBits) {
    std::array<std::size_t, (1u << kDigitBits) + 1> start{};  // start[d + 1]: how many have digit d, then the sum
    const auto digit = [&](std::int32_t v) {
      return static_cast<std::size_t>((position[static_cast<std::size_t>(v) - first] >> shift) & ((1u << kDigitBits) - 1));
    };
    for (const std::int32_t v : order) ++start[digit(v) + 1];
    for (std::size_t d = 1; d < start.size(); ++d) start[d] += start[d - 1];
    for (const std::int32_t v : order) sorted[start[digit(v)]++] = v;  // stable: keeps the lower digits' order
    order.swap(sorted);
  }
  return order;
}

int chessboard(const SampleTriangulation& s, std::int32_t a, std::int32_t b) {
  return std::max(std::abs(s.x(a) - s.x(b)), std::abs(s.y(a) - s.y(b)));
}

void flag_interpolable(SampleTriangulation& s, const SensorModel& model, const TriangulationParams& params) {
  s.interpolable.assign(s.triangles.size(), 0);
  for (std::size_t t = 0; t < s.triangles.size(); ++t) {
    const auto& v = s.triangles[t];
    float lo = s.vertex_depth_m[static_cast<std::size_t>(v[0])], hi = lo;
    for (int i = 1; i < 3; ++i) {
      lo = std::min(lo, s.vertex_depth_m[static_cast<std::size_t>(v[i])]);
      hi = std::max(hi, s.vertex_depth_m[static_cast<std::size_t>(v[i])]);
    }
    // A slanted surface spreads a triangle's depths by many sigma (a wall at 60 degrees and 2 m: ~1 sigma per
    // pixel) while its vertices still lie on their neighbours' plane; a step puts every vertex near it off
    // the plane of its neighbours, which straddle the step.
    const bool continuous = hi - lo <= params.discontinuity_sigmas * model.sigma_depth_at(hi) ||
                            s.non_planarity_sigmas(t) <= params.discontinuity_sigmas;
    s.interpolable[t] = continuous && s.longest_edge_columns(t) <= params.max_edge_columns;
  }
}

/// Normal equations of the least-squares plane w = a + b dx + c dy (w = 1/z, (dx, dy) the offset from the
/// vertex, so that a is the fit at the vertex) through a vertex's Delaunay neighbours, gathered triangle by
/// triangle: a neighbour counts once per triangle the two share, i.e. twice for every neighbour of an
/// interior vertex (the same fit as once each) and once for the two hull neighbours of a hull vertex.
/// The sums are exact integers (w in fixed point, kInverseDepthUnit: 2^-30 per metre, a depth step of
/// ~1e-9 z, at most ~2e-6 sigma), so they do not depend on the order of the triangles: a vertex's
/// residual is a function of the triangulation alone, whichever way it was built (SampleTriangulator).
/// Bounds: offsets below 2^20 px and fewer than 2^23 entries per vertex (2^22 samples) keep the m sums
/// below 2^63; w at most kMaxInverseDepth (depths below 1 um count as 1 um) keeps the r sums below 2^93.
constexpr double kInverseDepthUnit = 1.0 / (1 << 30), kMaxInverseDepth = 1 << 20;
struct PlaneSums {
  std::int64_t m00 = 0, m01 = 0, m02 = 0, m11 = 0, m12 = 0, m22 = 0;
  Int128 r0 = 0, r1 = 0, r2 = 0;
  void add(std::int64_t dx, std::int64_t dy, std::int64_t w) {
    m00 += 1;
    m01 += dx;
    m02 += dy;
    m11 += dx * dx;
    m12 += dx * dy;
    m22 += dy * dy;
    r0 += w;
    r1 += Int128{dx} * w;
    r2 += Int128{dy} * w;
  }
  /// The fit at the vertex in 1/m (Cramer's rule for a); false when the neighbours are collinear (or fewer
  /// than 3): the sums of integer offsets are exact, and so is the determinant computed from them in double
  /// while its products stay below 2^53 (offsets up to ~2^12 px): it is then exactly 0 for collinear
  /// neighbours and otherwise >= 1. (Beyond, rounding can leave collinear neighbours a determinant of 0.5
  /// or more and a meaningless fit: the same whatever the insertion order.)
  bool intercept(double& a) const {
    const auto d = [](auto v) { return static_cast<double>(v); };
    const double c0 = d(m11) * d(m22) - d(m12) * d(m12), c1 = d(m01) * d(m22) - d(m12) * d(m02),
                 c2 = d(m01) * d(m12) - d(m11) * d(m02);
    const double det = d(m00) * c0 - d(m01) * c1 + d(m02) * c2;
    if (det < 0.5) return false;
    a = kInverseDepthUnit * (d(r0) * c0 - d(m01) * (d(r1) * d(m22) - d(m12) * d(r2)) + d(m02) * (d(r1) * d(m12) - d(m11) * d(r2))) / det;
    return true;
  }
};

/// Leave-one-out residual of vertex v (header) from its plane sums.
float plane_residual_sigmas(const PlaneSums& sums, double z, const SensorModel& model) {
  double w_fit;
  if (!sums.intercept(w_fit)) return 0.0f;
  if (w_fit > 0) return static_cast<float>(std::abs(z - 1.0 / w_fit) / model.sigma_depth_at(1.0 / w_fit));
  return static_cast<float>(std::abs(1.0 / z - w_fit) * z * z / model.sigma_depth_at(z));  // plane behind the camera
}

std::int64_t fixed_inverse_depth(float z) {
  return std::llround(std::min(1.0 / z, kMaxInverseDepth) / kInverseDepthUnit);
}

// Every vertex's residual, gathering the entries triangle by triangle; `inverse` holds each vertex's
// fixed_inverse_depth.
void measure_non_planarity(SampleTriangulation& s, const std::vector<std::int64_t>& inverse, const SensorModel& model) {
  std::vector<PlaneSums> sums(s.vertex_count());
  for (const auto& t : s.triangles)
    for (int i = 0; i < 3; ++i) {
      const std::int32_t v = t[static_cast<std::size_t>(i)];
      for (const int k : {1, 2}) {
        const std::int32_t j = t[static_cast<std::size_t>((i + k) % 3)];
        sums[static_cast<std::size_t>(v)].add(s.x(j) - s.x(v), s.y(j) - s.y(v), inverse[static_cast<std::size_t>(j)]);
      }
    }
  s.residual_sigmas.assign(s.vertex_count(), 0.0f);
  for (std::size_t v = 0; v < s.vertex_count(); ++v)
    s.residual_sigmas[v] = plane_residual_sigmas(sums[v], s.vertex_depth_m[v], model);
}

// The residuals of `dirty` vertices only, gathering each one's entries around it in the triangulation: the
// same exact sums as measure_non_planarity's, so the same residuals.
void remeasure_non_planarity(SampleTriangulation& s, const Delaunay& d, const std::vector<std::int32_t>& dirty,
                             const std::vector<std::int64_t>& inverse, const SensorModel& model) {
  s.residual_sigmas.resize(s.vertex_count(), 0.0f);
  for (const std::int32_t v : dirty) {
    PlaneSums sums;
    d.for_each_neighbour_entry(v, [&](std::int32_t j) {
      sums.add(s.x(j) - s.x(v), s.y(j) - s.y(v), inverse[static_cast<std::size_t>(j)]);
    });
    s.residual_sigmas[static_cast<std::size_t>(v)] = plane_residual_sigmas(sums, s.vertex_depth_m[static_cast<std::size_t>(v)], model);
  }
}

}  // namespace

void check_sparse_depth_image(const std::vector<float>& depth, int width, int height) {
  detail::require_parameter(width > 0 && width <= kMaxSide, "width", width, "in [1, 2^20]");
  detail::require_parameter(height > 0 && height <= kMaxSide, "height", height, "in [1, 2^20]");
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  require_shape("sparse depth image", ColumnShape::of_arrays(width, height, {depth.size()}));
  // Negative or infinite (NaN is no sample): z < 0 or z > the largest float, as integer flags OR-ed without
  // an early exit, which the compiler vectorises (a bool || chain kept it scalar: 3 % of predict_depth).
  const auto bad = [](float z) {
    return static_cast<unsigned>(z < 0.0f) | static_cast<unsigned>(z > std::numeric_limits<float>::max());
  };
  unsigned any_bad = 0;
  for (std::size_t c = 0; c < n; ++c) any_bad |= bad(depth[c]);
  if (!any_bad) return;
  for (std::size_t c = 0; c < n; ++c)
    if (bad(depth[c]))
      throw InvalidInput("sparse depth image: pixel (" + std::to_string(c % static_cast<std::size_t>(width)) + ", " +
                         std::to_string(c / static_cast<std::size_t>(width)) + ") holds depth " +
                         std::to_string(depth[c]) + " (must be >= 0 and finite; 0 or NaN = no sample)");
}

double SampleTriangulation::area_px2(std::size_t t) const {
  const auto& v = triangles[t];
  const Point a{x(v[0]), y(v[0])}, b{x(v[1]), y(v[1])}, c{x(v[2]), y(v[2])};
  return 0.5 * static_cast<double>(orient(a, b, c));
}

int SampleTriangulation::longest_edge_columns(std::size_t t) const {
  const auto& v = triangles[t];
  return std::max({chessboard(*this, v[0], v[1]), chessboard(*this, v[1], v[2]), chessboard(*this, v[2], v[0])});
}

double SampleTriangulation::non_planarity_sigmas(std::size_t t) const {
  const auto& v = triangles[t];
  return std::max({residual_sigmas[static_cast<std::size_t>(v[0])], residual_sigmas[static_cast<std::size_t>(v[1])],
                   residual_sigmas[static_cast<std::size_t>(v[2])]});
}

ColumnIndex SampleTriangulation::centroid_column(std::size_t t) const {
  const auto& v = triangles[t];
  // round(s / 3) for a sum s >= 0 of pixel coordinates: s / 3 is never halfway, so (s + 1) / 3 in integers.
  const int cx = (x(v[0]) + x(v[1]) + x(v[2]) + 1) / 3, cy = (y(v[0]) + y(v[1]) + y(v[2]) + 1) / 3;
  return static_cast<ColumnIndex>(cy) * static_cast<ColumnIndex>(width) + static_cast<ColumnIndex>(cx);
}

SampleTriangulation triangulate_samples(const std::vector<float>& sparse_depth_m, int width, int height,
                                        const SensorModel& model, const TriangulationParams& params) {
  params.validate();
  check_sparse_depth_image(sparse_depth_m, width, height);
  return detail::triangulate_checked_samples(sparse_depth_m, width, height, model, params);
}

struct SampleTriangulator::State {
  SampleTriangulation out;
  Delaunay delaunay{true};
  std::vector<std::int32_t> depth_changed;  ///< vertices whose depth the last refresh changed
  /// fixed_inverse_depth of each vertex's depth, kept with the depths: a residual reads its neighbours'
  /// a dozen times each, and most vertices keep their depth from update to update.
  std::vector<std::int64_t> inverse_depth;
  /// Per pixel, the vertex there (-1: none); kept by a SampleTriangulator only. An update that does not
  /// start over starts the walk that inserts a new sample next to an inserted vertex, not next to the
  /// previous new sample, which a shot puts ~10 pixels away across a dense triangulation (measured: the
  /// insertion of 4 000 samples grew from 1 to 10 ms as the view filled). A start-over inserts as
  /// triangulate_samples does, so that it builds its triangles in its order.
  std::vector<std::int32_t> vertex_at;
  std::vector<std::uint8_t> dirty_mark;     ///< per vertex, all 0 between updates
  /// The model's depth noise the residuals were measured with (sigma_depth_at's parameters).
  std::array<double, 3> depth_noise{};
  std::size_t inserted_last = 0, lost_last = 0;
  bool started_over_last = false;
};

namespace {

// Removes the vertices whose pixel holds no sample any more and renumbers the others in order; false
// when a removal failed. Only a kept state (a SampleTriangulator's) has vertices to lose, so st.vertex_at
// is there to follow.
bool remove_lost(SampleTriangulator::State& st, const std::vector<std::int32_t>& lost) {
  SampleTriangulation& s = st.out;
  for (const std::int32_t v : lost) {
    if (!st.delaunay.remove(v)) return false;
    st.vertex_at[s.vertex_column[static_cast<std::size_t>(v)]] = -1;
  }
  std::vector<std::int32_t> renumbered(s.vertex_count(), 0);
  for (const std::int32_t v : lost) renumbered[static_cast<std::size_t>(v)] = -1;
  std::int32_t kept = 0;
  for (std::int32_t& r : renumbered) r = r < 0 ? -1 : kept++;
  st.delaunay.compact(renumbered);
  const auto keep = [&](auto& values) {
    std::size_t out = 0;
    for (std::size_t v = 0; v < renumbered.size(); ++v)
      if (renumbered[v] >= 0) values[out++] = values[v];
    values.resize(out);
  };
  keep(s.vertex_column);
  keep(s.vertex_x);
  keep(s.vertex_y);
  keep(s.vertex_depth_m);
  keep(s.residual_sigmas);
  keep(st.inverse_depth);
  for (std::size_t v = 0; v < s.vertex_count(); ++v) st.vertex_at[s.vertex_column[v]] = static_cast<std::int32_t>(v);
  std::vector<std::int32_t> changed;
  for (const std::int32_t v : st.depth_changed)
    if (renumbered[static_cast<std::size_t>(v)] >= 0) changed.push_back(renumbered[static_cast<std::size_t>(v)]);
  st.depth_changed.swap(changed);
  return true;
}

// Whether the state can take the image's samples by insertion: the same size (its vertices' depths
// refreshed, and those whose pixel holds no sample any more removed).
bool refresh_vertices(SampleTriangulator::State& st, const std::vector<float>& image, int width, int height) {
  SampleTriangulation& s = st.out;
  if (s.width != width || s.height != height) return false;  // a fresh state too: width 0
  st.depth_changed.clear();
  std::vector<std::int32_t> lost;
  for (std::size_t v = 0; v < s.vertex_count(); ++v) {
    const float z = image[s.vertex_column[v]];
    if (!(z > 0.0f)) {  // NaN too
      lost.push_back(static_cast<std::int32_t>(v));
      continue;
    }
    if (z != s.vertex_depth_m[v]) {
      st.depth_changed.push_back(static_cast<std::int32_t>(v));
      st.inverse_depth[v] = fixed_inverse_depth(z);
    }
    s.vertex_depth_m[v] = z;
  }
  st.lost_last = lost.size();
  // Many lost (a record's first returns replacing a full frame's samples): triangulating the rest anew is
  // cheaper than removing them one by one.
  if (lost.size() > s.vertex_count() / 8) return false;
  return lost.empty() || remove_lost(st, lost);
}

// The vertices whose residual may have changed since the last update: the new ones, those whose neighbours
// changed (the insertions' cavities), those whose depth changed and their neighbours; each once.
std::vector<std::int32_t> dirty_vertices(SampleTriangulator::State& st, std::size_t first_new) {
  const SampleTriangulation& s = st.out;
  st.dirty_mark.resize(s.vertex_count(), 0);
  std::vector<std::int32_t> dirty;
  const auto mark = [&](std::int32_t v) {
    if (!st.dirty_mark[static_cast<std::size_t>(v)]) {
      st.dirty_mark[static_cast<std::size_t>(v)] = 1;
      dirty.push_back(v);
    }
  };
  for (std::size_t v = first_new; v < s.vertex_count(); ++v) mark(static_cast<std::int32_t>(v));
  for (const std::int32_t v : st.delaunay.take_touched()) mark(v);
  for (const std::int32_t v : st.depth_changed) {
    mark(v);
    st.delaunay.for_each_neighbour_entry(v, mark);
  }
  for (const std::int32_t v : dirty) st.dirty_mark[static_cast<std::size_t>(v)] = 0;
  return dirty;
}

// An inserted vertex within kNearVertexPixels (chessboard) of vertex v, nearest rings first; -1 when none.
// Reads st.vertex_at (a SampleTriangulator's). Once the view holds a sample every few pixels a new one
// almost always has one; the first shots' sparse samples often do not, and walk from the last new
// triangle as before.
constexpr int kNearVertexPixels = 3;
std::int32_t inserted_vertex_near(const SampleTriangulator::State& st, std::int32_t v) {
  const SampleTriangulation& s = st.out;
  const int x = s.x(v), y = s.y(v);
  for (int r = 1; r <= kNearVertexPixels; ++r)
    for (int dy = -r; dy <= r; ++dy) {
      const int yy = y + dy;
      if (yy < 0 || yy >= s.height) continue;
      const int step = dy == -r || dy == r ? 1 : 2 * r;  // the ring: whole first and last rows, else two ends
      for (int dx = -r; dx <= r; dx += step) {
        const int xx = x + dx;
        if (xx < 0 || xx >= s.width) continue;
        const std::int32_t u = st.vertex_at[static_cast<std::size_t>(yy) * static_cast<std::size_t>(s.width) + static_cast<std::size_t>(xx)];
        if (u >= 0 && st.delaunay.inserted(u)) return u;
      }
    }
  return -1;
}

// Brings `st` to the image's samples (checked by the caller): the lost ones removed, the new ones appended
// in column order and inserted in Hilbert order. With `keep` (SampleTriangulator), the insertions after this
// update record the vertices whose neighbours change, for the next update's residuals (a start-over's own
// insertions need none: it measures every residual).
void update_state(SampleTriangulator::State& st, const std::vector<float>& image, int width, int height,
                  const SensorModel& model, const TriangulationParams& params, bool keep) {
  st.started_over_last = !refresh_vertices(st, image, width, height);
  if (st.started_over_last) {
    st.out = SampleTriangulation{};
    st.inverse_depth.clear();
    if (keep) st.vertex_at.assign(image.size(), -1);
    st.out.width = width;
    st.out.height = height;
    st.delaunay = Delaunay(width < kSmallSide && height < kSmallSide);
  }
  SampleTriangulation& s = st.out;
  // Where there are vertices already (only a kept state has any: a fresh one started over).
  const std::int32_t* known = st.started_over_last ? nullptr : st.vertex_at.data();
  std::int32_t* vertex_at = keep ? st.vertex_at.data() : nullptr;
  // Samples without a vertex, counted, then appended in column order (two instantiations: with and
  // without `known`, so that the counting loop vectorises). NaN fails `z > 0`.
  const auto append_new = [&](auto is_new) {
    std::size_t added = 0;
    for (std::size_t c = 0; c < image.size(); ++c) added += is_new(c);
    if (s.vertex_count() + added >= (std::size_t{1} << 22))
      throw InvalidInput("triangulate_samples: " + std::to_string(s.vertex_count() + added) + " samples (at most 2^22)");
    const std::size_t total = s.vertex_count() + added;
    reserve_geometric(s.vertex_column, total);
    reserve_geometric(s.vertex_x, total);
    reserve_geometric(s.vertex_y, total);
    reserve_geometric(s.vertex_depth_m, total);
    reserve_geometric(st.inverse_depth, total);
    st.delaunay.reserve(total);
    std::size_t c = 0;
    for (std::int32_t y = 0; y < height; ++y)
      for (std::int32_t x = 0; x < width; ++x, ++c)
        if (is_new(c)) {
          if (vertex_at) vertex_at[c] = static_cast<std::int32_t>(s.vertex_column.size());
          s.vertex_column.push_back(static_cast<ColumnIndex>(c));
          s.vertex_x.push_back(x);
          s.vertex_y.push_back(y);
          s.vertex_depth_m.push_back(image[c]);
          st.inverse_depth.push_back(fixed_inverse_depth(image[c]));
          st.delaunay.add({x, y});
        }
    return added;
  };
  const std::size_t first_new = s.vertex_count();
  const std::size_t added = known ? append_new([&](std::size_t c) { return (image[c] > 0.0f) & (known[c] < 0); })
                                  : append_new([&](std::size_t c) { return image[c] > 0.0f; });
  const std::vector<std::int32_t> order = insertion_order(s, first_new);
  for (std::size_t k = 0; k < order.size(); ++k) {
    poll_stop(k);
    st.delaunay.insert(order[k], known ? inserted_vertex_near(st, order[k]) : -1);
  }
  st.inserted_last = added;
  st.delaunay.vertex_triangles(s.triangles);
  // Residuals: all of them after a start-over, with another model's noise, or where most changed (a pass
  // over the triangles is then cheaper than a walk around each vertex), else those of the dirty vertices.
  const SensorModelParams& noise = model.params();
  const std::array<double, 3> depth_noise{noise.sigma_depth_m, noise.sigma_depth_per_m2, noise.sigma_depth_floor_m};
  const bool same_noise = depth_noise == st.depth_noise;
  st.depth_noise = depth_noise;
  const std::vector<std::int32_t> dirty = st.started_over_last ? std::vector<std::int32_t>{} : dirty_vertices(st, first_new);
  if (st.started_over_last || !same_noise || 2 * dirty.size() > s.vertex_count())
    measure_non_planarity(s, st.inverse_depth, model);
  else
    remeasure_non_planarity(s, st.delaunay, dirty, st.inverse_depth, model);
  flag_interpolable(s, model, params);
  st.delaunay.track_touched(keep);
}

}  // namespace

SampleTriangulation detail::triangulate_checked_samples(const std::vector<float>& sparse_depth_m, int width, int height,
                                                        const SensorModel& model, const TriangulationParams& params) {
  SampleTriangulator::State st;
  update_state(st, sparse_depth_m, width, height, model, params, false);
  return std::move(st.out);
}

SampleTriangulator::SampleTriangulator() = default;
SampleTriangulator::~SampleTriangulator() = default;
SampleTriangulator::SampleTriangulator(SampleTriangulator&&) noexcept = default;
SampleTriangulator& SampleTriangulator::operator=(SampleTriangulator&&) noexcept = default;

const SampleTriangulation& SampleTriangulator::update(const std::vector<float>& sparse_depth_m, int width, int height,
                                                      const SensorModel& model, const TriangulationParams& params) {
  params.validate();
  check_sparse_depth_image(sparse_depth_m, width, height);
  if (!state_) state_ = std::make_unique<State>();
  try {
    update_state(*state_, sparse_depth_m, width, height, model, params, true);
  } catch (...) {
    state_.reset();  // interrupted (cancel, too many samples): the next update starts over
    throw;
  }
  ++updates_;
  start_overs_ += state_->started_over_last;
  return state_->out;
}

const SampleTriangulation& SampleTriangulator::triangulation() const {
  static const SampleTriangulation kNone;
  return state_ ? state_->out : kNone;
}

std::size_t SampleTriangulator::inserted_last() const { return state_ ? state_->inserted_last : 0; }
std::size_t SampleTriangulator::removed_last() const {
  return state_ && !state_->started_over_last ? state_->lost_last : 0;
}
bool SampleTriangulator::started_over_last() const { return state_ && state_->started_over_last; }

std::vector<std::size_t> top_scored_triangles(const SampleTriangulation& triangulation, std::size_t count) {
  std::vector<std::pair<double, std::size_t>> scored;
  for (std::size_t t = 0; t < triangulation.triangles.size(); ++t) {
    const double s = triangulation.score(t);
    if (s > 0) scored.emplace_back(-s, t);
  }
  count = std::min(count, scored.size());
  std::partial_sort(scored.begin(), scored.begin() + static_cast<std::ptrdiff_t>(count), scored.end());
  std::vector<std::size_t> out(count);
  for (std::size_t k = 0; k < count; ++k) out[k] = scored[k].second;
  return out;
}

}  // namespace occ_improve
