#include "sim/site_generator.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <numeric>
#include <random>
#include <sstream>
#include <stdexcept>

#include "sim/floor_plan.h"
#include "sim/robot.h"

namespace sarmap {
namespace sim {
namespace {

constexpr double kWallThicknessM = 0.1;
constexpr double kDeg = M_PI / 180.0;

// Uniform and normal numbers from mt19937_64's standard-fixed output (the standard library's
// distributions differ between implementations).
class Random {
 public:
  explicit Random(uint64_t seed) : engine_(seed) {}
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  int Int(int lo, int hi) {  // [lo, hi]
    return std::min(hi, lo + static_cast<int>(std::floor(Uniform() * (hi - lo + 1))));
  }
  bool Chance(double p) { return Uniform() < p; }
  // Box-Muller: sqrt(-2 ln u1) cos(2 pi u2) is N(0, 1) for independent uniforms u1 in (0, 1].
  double Normal() {
    const double u1 = 1.0 - Uniform(), u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  template <class T>
  void Shuffle(std::vector<T>* v) {  // Fisher-Yates
    for (int i = static_cast<int>(v->size()) - 1; i > 0; --i) std::swap((*v)[i], (*v)[Int(0, i)]);
  }

 private:
  std::mt19937_64 engine_;
};

// SplitMix64 finaliser: decorrelates the seeds of successive attempts.
uint64_t Mix(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

double Mm(double x) { return std::round(x * 1000.0) / 1000.0; }
double Cm(double x) { return std::round(x * 100.0) / 100.0; }
Eigen::Vector2d Mm(const Eigen::Vector2d& p) { return {Mm(p.x()), Mm(p.y())}; }
// Colour from 0..255 components, as the world loader converts them.
Rgb Colour(double r, double g, double b) {
  return Rgb{static_cast<float>(std::round(r) / 255), static_cast<float>(std::round(g) / 255),
             static_cast<float>(std::round(b) / 255)};
}
Rgb Vary(Random* rng, double r, double g, double b, double spread = 18) {
  const auto c = [&](double v) {
    return std::clamp(v + rng->Uniform(-spread, spread), 0.0, 255.0);
  };
  return Colour(c(r), c(g), c(b));
}

// An axis-aligned rectangle of the floor.
struct Rect {
  Eigen::Vector2d lo, hi;
  bool Overlaps(const Rect& o, double margin = 0) const {
    return lo.x() < o.hi.x() + margin && o.lo.x() < hi.x() + margin && lo.y() < o.hi.y() + margin &&
           o.lo.y() < hi.y() + margin;
  }
  double Distance(const Eigen::Vector2d& p) const {
    const Eigen::Vector2d d = (lo - p).cwiseMax(p - hi).cwiseMax(Eigen::Vector2d::Zero());
    return d.norm();
  }
  bool Contains(const Rect& o) const {
    return o.lo.x() >= lo.x() && o.lo.y() >= lo.y() && o.hi.x() <= hi.x() && o.hi.y() <= hi.y();
  }
};

Rect BoundsOf(const Eigen::Vector2d& centre, const Eigen::Vector2d& size, double yaw) {
  const double c = std::abs(std::cos(yaw)), s = std::abs(std::sin(yaw));
  const Eigen::Vector2d half(0.5 * (c * size.x() + s * size.y()),
                             0.5 * (s * size.x() + c * size.y()));
  return {centre - half, centre + half};
}

// A piece of furniture or debris while the site is built: removable ones go first when a room
// is cut off (debris before furniture, the last placed first).
struct Item {
  enum Kind { kFixed, kFurniture, kDebris } kind;
  bool is_table = false;
  Box box;
  Table table;
  Rect bounds;
  bool hums = false;  // a machine: `noise` sounds from it
  SoundSource noise;
};

struct Door {
  Rect keepout;  // the gap and 1 m of floor on both sides
};

class Builder {
 public:
  Builder(const SiteOptions& options, uint64_t seed)
      : o_(options), rng_(seed), extra_rng_(seed ^ 0x6d75736963ULL) {}

  bool Build(Site* site);

 private:
  void Layout();
  void AddWall(const std::string& name, Eigen::Vector2d a, Eigen::Vector2d b,
               std::vector<std::pair<double, double>> gaps);
  double DoorWidth() { return Cm(rng_.Uniform(o_.door_width_min_m, o_.door_width_max_m)); }
  void AddDoorKeepout(const Eigen::Vector2d& centre, bool wall_along_x, double width);
  bool Free(const Rect& r, double margin) const;
  Rect Interior(const SiteRoom& room) const {
    const double h = 0.5 * kWallThicknessM + 0.02;
    return {room.min + Eigen::Vector2d(h, h), room.max - Eigen::Vector2d(h, h)};
  }
  bool PlaceHidden(int room);
  bool PlaceAgainstWall(int room, Item item, const Eigen::Vector2d& size);
  bool PlaceTable(int room);
  bool PlaceDebris();
  int PickRoom(bool with_corridor);
  World CurrentWorld(bool with_people) const;
  bool AllRoomsReachable(const World& world, bool people_block) const;
  bool Repair();
  bool PlacePeople(int visible);
  void AddSounds();
  void Finish(Site* site);

  const SiteOptions& o_;
  Random rng_;
  Random extra_rng_;  // music and beepers: their own stream, so the layout does not depend on them
  double length_ = 0, depth_ = 0, height_ = 2.6;
  std::vector<SiteRoom> rooms_;
  std::vector<Wall> walls_;
  std::vector<Door> doors_;
  std::vector<Rect> keepouts_;
  std::vector<Item> items_;
  std::vector<Person> people_;
  std::vector<int> hidden_;
  Rgb wall_colour_;
  Eigen::Vector3d start_{0, 0, 0};
  std::vector<SoundSource> sources_;
};

void Builder::AddWall(const std::string& name, Eigen::Vector2d a, Eigen::Vector2d b,
                      std::vector<std::pair<double, double>> gaps) {
  // Gaps are distances along the wall from a; the wall is drawn between them.
  std::sort(gaps.begin(), gaps.end());
  const double length = (b - a).norm();
  const Eigen::Vector2d dir = (b - a) / length;
  double at = 0;
  int piece = 0;
  gaps.emplace_back(length, length);
  for (const auto& gap : gaps) {
    if (gap.first - at > 0.05) {
      Wall w;
      w.name = name + (gaps.size() > 1 ? "_" + std::to_string(++piece) : "");
      w.from = Mm(a + at * dir);
      w.to = Mm(a + gap.first * dir);
      w.height_m = height_;
      w.thickness_m = kWallThicknessM;
      w.colour = wall_colour_;
      walls_.push_back(w);
    }
    at = gap.second;
  }
}

void Builder::AddDoorKeepout(const Eigen::Vector2d& centre, bool wall_along_x, double width) {
  const Eigen::Vector2d half = wall_along_x ? Eigen::Vector2d(0.5 * width + 0.15, 1.0)
                                            : Eigen::Vector2d(1.0, 0.5 * width + 0.15);
  doors_.push_back({{centre - half, centre + half}});
  keepouts_.push_back(doors_.back().keepout);
}

void Builder::Layout() {
  // Footprint: L * D = area with L / D = aspect.
  const double aspect = rng_.Uniform(1.1, 1.7);
  length_ = std::round(std::sqrt(o_.floor_area_m2 * aspect) * 10) / 10;
  depth_ = std::round(o_.floor_area_m2 / length_ * 10) / 10;
  height_ = Cm(rng_.Uniform(o_.wall_height_min_m, o_.wall_height_max_m));
  wall_colour_ = Vary(&rng_, 215, 210, 198, 12);
  const double corridor_w = Cm(rng_.Uniform(o_.corridor_width_min_m, o_.corridor_width_max_m));
  const double min_room_depth = 2.3, min_room_width = 2.4;
  // A hall across the east end when the building is long enough.
  double hall_w = 0;
  if (length_ >= 12 && rng_.Chance(0.5))
    hall_w = Cm(rng_.Uniform(3.5, std::min(6.0, 0.3 * length_)));
  const double corridor_end = length_ - hall_w;
  // Two rows of rooms when both can be min_room_depth deep, else one row north of the corridor.
  const bool two_rows = depth_ - corridor_w >= 2 * min_room_depth + 0.4;
  const double y0 =
      two_rows
          ? Cm(min_room_depth + (depth_ - corridor_w - 2 * min_room_depth) * rng_.Uniform(0.3, 0.7))
          : 0.0;
  const double y1 = y0 + corridor_w;
  SiteRoom corridor{"corridor", {0, y0}, {corridor_end, y1}, true};
  rooms_.push_back(corridor);
  // Rooms per row: widths about U(3.5, 5) m, more when min_rooms asks for them.
  const int rows = two_rows ? 2 : 1;
  const int max_per_row = std::max(1, static_cast<int>(std::floor(corridor_end / min_room_width)));
  std::vector<int> per_row(rows);
  for (int r = 0; r < rows; ++r) {
    per_row[r] = std::clamp(static_cast<int>(std::ceil(corridor_end / rng_.Uniform(3.5, 5.0))), 1,
                            max_per_row);
  }
  const int needed = o_.min_rooms - (hall_w > 0 ? 1 : 0);
  for (int k = 0; std::accumulate(per_row.begin(), per_row.end(), 0) < needed && k < 100; ++k) {
    int& fewest = *std::min_element(per_row.begin(), per_row.end());
    if (fewest < max_per_row) ++fewest;
  }
  // Outer walls (a closed rectangle).
  const Eigen::Vector2d c00(0, 0), c10(length_, 0), c11(length_, depth_), c01(0, depth_);
  AddWall("outer_south", c00, c10, {});
  AddWall("outer_east", c10, c11, {});
  AddWall("outer_north", c11, c01, {});
  AddWall("outer_west", c01, c00, {});
  std::vector<std::pair<double, double>> corridor_gaps[2];  // south and north corridor walls
  for (int r = 0; r < rows; ++r) {
    const bool south = two_rows && r == 0;
    const double ylo = south ? 0.0 : y1, yhi = south ? y0 : depth_;
    const int n = per_row[r];
    const double step = corridor_end / n;
    const double jitter = std::min(0.6, 0.5 * (step - min_room_width));
    std::vector<double> cuts{0.0};
    for (int i = 1; i < n; ++i) cuts.push_back(Cm(i * step + rng_.Uniform(-jitter, jitter)));
    cuts.push_back(corridor_end);
    for (int i = 0; i < n; ++i) {
      SiteRoom room;
      room.name = "room" + std::to_string(rooms_.size());
      room.min = {cuts[i], ylo};
      room.max = {cuts[i + 1], yhi};
      rooms_.push_back(room);
      // Its door onto the corridor, at least 0.3 m from the dividing walls.
      const double w = DoorWidth();
      const double lo = cuts[i] + 0.3 + 0.5 * w, hi = cuts[i + 1] - 0.3 - 0.5 * w;
      const double x = Cm(lo < hi ? rng_.Uniform(lo, hi) : 0.5 * (cuts[i] + cuts[i + 1]));
      corridor_gaps[south ? 0 : 1].emplace_back(x - 0.5 * w, x + 0.5 * w);
      AddDoorKeepout({x, south ? y0 : y1}, true, w);
    }
    // Dividing walls, some with a door to the neighbour (away from the corridor).
    for (int i = 1; i < n; ++i) {
      std::vector<std::pair<double, double>> gaps;
      const double span = yhi - ylo;
      const double w = DoorWidth();
      if (span >= w + 1.4 && rng_.Chance(0.35)) {
        // Distance along the wall from its start (at the corridor side).
        const double at = Cm(rng_.Uniform(0.9 + 0.5 * w, span - 0.3 - 0.5 * w));
        gaps.emplace_back(at - 0.5 * w, at + 0.5 * w);
        const double y = south ? y0 - at : y1 + at;
        AddDoorKeepout({cuts[i], y}, false, w);
      }
      const Eigen::Vector2d from(cuts[i], south ? y0 : y1), to(cuts[i], south ? 0.0 : depth_);
      AddWall(rooms_[rooms_.size() - n + i].name + "_west", from, to, gaps);
    }
  }
  if (hall_w > 0) {
    SiteRoom hall{"hall", {corridor_end, 0}, {length_, depth_}, false};
    rooms_.push_back(hall);
    const double w = std::min(DoorWidth(), corridor_w - 0.2);
    const double yc = 0.5 * (y0 + y1);
    AddWall("hall_west", {corridor_end, 0}, {corridor_end, depth_}, {{yc - 0.5 * w, yc + 0.5 * w}});
    AddDoorKeepout({corridor_end, yc}, false, w);
  }
  if (two_rows) AddWall("corridor_south", {0, y0}, {corridor_end, y0}, corridor_gaps[0]);
  AddWall("corridor_north", {0, y1}, {corridor_end, y1}, corridor_gaps[1]);
  // The robot starts in the corridor near its west end, facing along it.
  start_ = {Mm(rng_.Uniform(0.8, std::min(2.0, corridor_end - 0.8))), Mm(0.5 * (y0 + y1)), 0.0};
  keepouts_.push_back(
      {start_.head<2>() - Eigen::Vector2d(0.8, 0.8), start_.head<2>() + Eigen::Vector2d(0.8, 0.8)});
  // Room centres stay clear, so that the robot can be sent to each.
  for (const SiteRoom& room : rooms_) {
    if (room.corridor) continue;
    keepouts_.push_back(
        {room.Centre() - Eigen::Vector2d(0.6, 0.6), room.Centre() + Eigen::Vector2d(0.6, 0.6)});
  }
}

bool Builder::Free(const Rect& r, double margin) const {
  for (const Rect& k : keepouts_) {
    if (r.Overlaps(k, 0)) return false;
  }
  for (const Item& it : items_) {
    if (r.Overlaps(it.bounds, margin)) return false;
  }
  return true;
}

int Builder::PickRoom(bool with_corridor) {
  // Weighted by area (the corridor counts half).
  double total = 0;
  for (const SiteRoom& r : rooms_)
    total += (r.corridor ? (with_corridor ? 0.5 : 0.0) : 1.0) * r.Area();
  double u = rng_.Uniform(0, total);
  for (size_t i = 0; i < rooms_.size(); ++i) {
    const double w = (rooms_[i].corridor ? (with_corridor ? 0.5 : 0.0) : 1.0) * rooms_[i].Area();
    if (u < w) return static_cast<int>(i);
    u -= w;
  }
  return static_cast<int>(rooms_.size()) - 1;
}

// A corner pocket: the person at distance 0.45 m from the corner along the bisector u, a tall
// screen across the corner centred 1.0 m out along u, perpendicular to it, 1.4 m long (its ends
// stop 7 cm short of the walls: no gap the robot or a line of sight at its height gets through).
bool Builder::PlaceHidden(int room_index) {
  const SiteRoom& room = rooms_[room_index];
  if (room.corridor || (room.max - room.min).minCoeff() < 2.6) return false;
  const Rect in = Interior(room);
  for (int attempt = 0; attempt < 4; ++attempt) {
    const int corner = rng_.Int(0, 3);
    const double sx = corner & 1 ? -1 : 1, sy = corner & 2 ? -1 : 1;
    const Eigen::Vector2d k(sx > 0 ? in.lo.x() : in.hi.x(), sy > 0 ? in.lo.y() : in.hi.y());
    const Rect pocket{k.cwiseMin(k + Eigen::Vector2d(1.45 * sx, 1.45 * sy)),
                      k.cwiseMax(k + Eigen::Vector2d(1.45 * sx, 1.45 * sy))};
    if (!Free(pocket, 0.1)) continue;
    const Eigen::Vector2d u = Eigen::Vector2d(sx, sy) / std::sqrt(2.0);
    Item screen;
    screen.kind = Item::kFixed;
    screen.box.name = "screen";
    screen.box.centre = Mm(k + 1.0 * u);
    screen.box.yaw_rad = std::atan2(sy, -sx);  // along v = (-sx, sy) / sqrt(2), perpendicular to u
    screen.box.yaw_rad = std::round(screen.box.yaw_rad / kDeg) * kDeg;
    screen.box.size_m = {1.4, 0.4, Cm(rng_.Uniform(1.95, 2.1))};
    screen.box.colour = Vary(&rng_, 150, 150, 160);
    screen.bounds = pocket;
    items_.push_back(screen);
    Person p;
    p.position = Mm(k + 0.45 * u);
    p.yaw_rad = std::round(std::atan2(u.y(), u.x()) / kDeg) * kDeg;  // facing out of the corner
    p.posture = rng_.Chance(0.7) ? Posture::kSitting : Posture::kStanding;
    p.height_m = Cm(rng_.Uniform(1.55, 1.85));
    people_.push_back(p);
    hidden_.push_back(static_cast<int>(people_.size()) - 1);
    return true;
  }
  return false;
}

// A box with its long side along one of the room's walls, `size` = (along, across, height).
bool Builder::PlaceAgainstWall(int room_index, Item item, const Eigen::Vector2d& size) {
  const Rect in = Interior(rooms_[room_index]);
  for (int attempt = 0; attempt < 25; ++attempt) {
    const int side = rng_.Int(0, 3);  // south, north, west, east
    const bool along_x = side < 2;
    const double room_along = along_x ? in.hi.x() - in.lo.x() : in.hi.y() - in.lo.y();
    const double room_across = along_x ? in.hi.y() - in.lo.y() : in.hi.x() - in.lo.x();
    if (room_along < size.x() + 0.1 || room_across < size.y() + 1.2) return false;
    const double t = rng_.Uniform(0.5 * size.x(), room_along - 0.5 * size.x());
    Eigen::Vector2d c;
    if (along_x)
      c = {in.lo.x() + t, side == 0 ? in.lo.y() + 0.5 * size.y() : in.hi.y() - 0.5 * size.y()};
    else
      c = {side == 2 ? in.lo.x() + 0.5 * size.y() : in.hi.x() - 0.5 * size.y(), in.lo.y() + t};
    c = Mm(c);
    const Eigen::Vector2d extent = along_x ? size : Eigen::Vector2d(size.y(), size.x());
    const Rect r{c - 0.5 * extent, c + 0.5 * extent};
    if (!Free(r, 0.1)) continue;
    item.box.centre = c;
    item.box.yaw_rad = along_x ? 0.0 : 90 * kDeg;
    item.bounds = r;
    items_.push_back(item);
    return true;
  }
  return false;
}

bool Builder::PlaceTable(int room_index) {
  const Rect in = Interior(rooms_[room_index]);
  const Eigen::Vector2d size(Cm(rng_.Uniform(1.2, 1.8)), Cm(rng_.Uniform(0.7, 0.9)));
  for (int attempt = 0; attempt < 25; ++attempt) {
    const bool along_x = rng_.Chance(0.5);
    const Eigen::Vector2d extent = along_x ? size : Eigen::Vector2d(size.y(), size.x());
    if ((in.hi - in.lo - extent).minCoeff() < 0.2) return false;
    const Eigen::Vector2d c = Mm(
        Eigen::Vector2d(rng_.Uniform(in.lo.x() + 0.5 * extent.x(), in.hi.x() - 0.5 * extent.x()),
                        rng_.Uniform(in.lo.y() + 0.5 * extent.y(), in.hi.y() - 0.5 * extent.y())));
    const Rect r{c - 0.5 * extent, c + 0.5 * extent};
    if (!Free(r, 0.3)) continue;
    Item item;
    item.kind = Item::kFurniture;
    item.is_table = true;
    item.table.name = "table";
    item.table.centre = c;
    item.table.yaw_rad = along_x ? 0.0 : 90 * kDeg;
    item.table.size_m = size;
    item.table.height_m = Cm(rng_.Uniform(0.72, 0.78));
    item.table.colour = Vary(&rng_, 140, 108, 76);
    item.bounds = r;
    items_.push_back(item);
    return true;
  }
  return false;
}

bool Builder::PlaceDebris() {
  const int room_index = PickRoom(true);
  const Rect in = Interior(rooms_[room_index]);
  Item item;
  item.kind = Item::kDebris;
  const double kind = rng_.Uniform();
  if (kind < 0.45) {
    item.box.name = "debris";
    item.box.size_m = {Cm(rng_.Uniform(0.2, 0.5)), Cm(rng_.Uniform(0.2, 0.5)),
                       Cm(rng_.Uniform(0.1, 0.4))};
    item.box.colour = Vary(&rng_, 120, 110, 100, 30);
  } else if (kind < 0.8) {
    item.box.name = "rubble";
    item.box.size_m = {Cm(rng_.Uniform(0.6, 1.2)), Cm(rng_.Uniform(0.4, 0.8)),
                       Cm(rng_.Uniform(0.08, 0.2))};
    item.box.colour = Vary(&rng_, 150, 145, 135, 20);
  } else {
    item.box.name = "fallen_shelf";
    item.box.size_m = {Cm(rng_.Uniform(1.6, 2.0)), 0.4, 0.35};
    item.box.colour = Vary(&rng_, 120, 90, 60);
  }
  for (int attempt = 0; attempt < 25; ++attempt) {
    const double yaw = rng_.Int(0, 179) * kDeg;
    const Rect b0 = BoundsOf(Eigen::Vector2d::Zero(), item.box.size_m.head<2>(), yaw);
    const Eigen::Vector2d half = b0.hi;
    if ((in.hi - in.lo - 2 * half).minCoeff() < 0) continue;
    const Eigen::Vector2d c =
        Mm(Eigen::Vector2d(rng_.Uniform(in.lo.x() + half.x(), in.hi.x() - half.x()),
                           rng_.Uniform(in.lo.y() + half.y(), in.hi.y() - half.y())));
    const Rect r{c - half, c + half};
    if (!Free(r, 0.05)) continue;
    item.box.centre = c;
    item.box.yaw_rad = yaw;
    item.bounds = r;
    items_.push_back(item);
    return true;
  }
  return false;
}

World Builder::CurrentWorld(bool with_people) const {
  World w;
  w.walls = walls_;
  for (const Item& it : items_) {
    if (it.is_table)
      w.tables.push_back(it.table);
    else
      w.boxes.push_back(it.box);
  }
  if (with_people) w.people = people_;
  w.robot.pose = start_;
  return w;
}

bool Builder::AllRoomsReachable(const World& world, bool people_block) const {
  // With a margin: a robot that plans on a measured map (walls a little thicker than they are)
  // must still find the way.
  const GridMap g = ReachableFloor(world, o_.robot_radius_m + o_.passage_margin_m, 0.05, people_block);
  for (const SiteRoom& room : rooms_) {
    if (CellAt(g, room.Centre()) != 0) return false;
  }
  return true;
}

// Removes debris, then furniture, last placed first, until every room is reachable.
bool Builder::Repair() {
  for (Item::Kind kind : {Item::kDebris, Item::kFurniture}) {
    while (!AllRoomsReachable(CurrentWorld(false), false)) {
      int last = -1;
      for (int i = static_cast<int>(items_.size()) - 1; i >= 0 && last < 0; --i) {
        if (items_[i].kind == kind) last = i;
      }
      if (last < 0) break;
      items_.erase(items_.begin() + last);
    }
  }
  return AllRoomsReachable(CurrentWorld(false), false);
}

// People in view: on reachable floor, clear of furniture (bodies sampled every 0.15 m, 0.3 m
// from every obstacle line beyond its half-width), not in front of doors or on room centres,
// 0.8 m apart, and never cutting a room off (checked with the people as obstacles).
bool Builder::PlacePeople(int visible) {
  const World bare = CurrentWorld(false);
  const GridMap floor = ReachableFloor(bare, o_.robot_radius_m, 0.05, false);
  const std::vector<Obstacle> obstacles = CollisionObstacles(bare, false);
  for (int placed = 0, tries = 0; placed < visible; ++tries) {
    if (tries > 60 * visible) return false;
    const int room_index = PickRoom(true);
    const Rect in = Interior(rooms_[room_index]);
    Person p;
    const double u = rng_.Uniform();
    p.posture = u < 0.4 ? Posture::kStanding : u < 0.7 ? Posture::kSitting : Posture::kLying;
    p.height_m = Cm(rng_.Uniform(1.55, 1.9));
    p.yaw_rad = rng_.Int(0, 359) * kDeg;
    if (p.yaw_rad > M_PI) p.yaw_rad -= 360 * kDeg;
    const double margin = p.posture == Posture::kLying ? 1.0 : 0.4;
    if ((in.hi - in.lo).minCoeff() < 2 * margin + 0.1) continue;
    p.position = Mm(Eigen::Vector2d(rng_.Uniform(in.lo.x() + margin, in.hi.x() - margin),
                                    rng_.Uniform(in.lo.y() + margin, in.hi.y() - margin)));
    if (CellAt(floor, p.position) != 0) continue;
    const Eigen::Vector2d dir(std::cos(p.yaw_rad), std::sin(p.yaw_rad));
    const Rect around{p.position - Eigen::Vector2d(margin, margin),
                      p.position + Eigen::Vector2d(margin, margin)};
    bool ok = true;
    for (const Rect& k : keepouts_) ok = ok && !around.Overlaps(k);
    for (const Person& q : people_)
      ok = ok && (q.position - p.position).norm() > 0.8 + (q.posture == Posture::kLying ? 0.9 : 0);
    for (double s = p.posture == Posture::kLying ? -0.95 : 0.0;
         ok && s <= (p.posture == Posture::kLying ? 0.86 : 0.0); s += 0.15) {
      ok = !CircleCollides(p.position + s * dir, 0.3, obstacles);
    }
    if (!ok) continue;
    people_.push_back(p);
    if (!AllRoomsReachable(CurrentWorld(true), true)) {
      people_.pop_back();
      continue;
    }
    ++placed;
  }
  return true;
}

void Builder::AddSounds() {
  const std::vector<std::string> pool = {"espeak:help",
                                         "espeak:I am here",
                                         "espeak:over here",
                                         "audio/cmu_arctic/cmu_arctic_us_aew_a0001.wav",
                                         "audio/pocketsphinx_test/goforward.raw",
                                         "audio/cmu_arctic/cmu_arctic_us_axb_a0004.wav"};
  for (size_t i = 0; i < people_.size(); ++i) {
    const bool hidden =
        std::find(hidden_.begin(), hidden_.end(), static_cast<int>(i)) != hidden_.end();
    if (!hidden && !rng_.Chance(o_.voice_probability)) continue;
    SoundSource s;
    s.name = people_[i].name + "_voice";
    s.kind = SourceKind::kVoice;
    s.person_id = people_[i].id;
    s.position = people_[i].Mouth();
    s.level_db_spl = std::round(rng_.Uniform(62, 70));
    std::vector<std::string> clips = pool;
    rng_.Shuffle(&clips);
    clips.resize(rng_.Int(2, 3));
    if (hidden && std::find(clips.begin(), clips.end(), "espeak:help") == clips.end())
      clips[0] = "espeak:help";
    s.clips = clips;
    s.start_s = std::round(rng_.Uniform(0.5, 6.0) * 10) / 10;
    s.every_s = std::round(rng_.Uniform(6.0, 15.0));
    sources_.push_back(s);
  }
  if (rng_.Chance(o_.alarm_probability)) {
    const SiteRoom& c = rooms_[0];
    SoundSource s;
    s.name = "alarm";
    s.kind = SourceKind::kAlarm;
    s.position = {Mm(rng_.Uniform(c.min.x() + 0.5, c.max.x() - 0.5)), Mm(c.max.y() - 0.1), 2.2};
    s.level_db_spl = std::round(rng_.Uniform(70, 80));
    s.start_s = std::round(rng_.Uniform(2, 15));
    s.every_s = std::round(rng_.Uniform(20, 40));
    s.duration_s = std::round(rng_.Uniform(3, 6));
    // A beeper or the siren, from their own stream: the layout does not depend on it.
    if (extra_rng_.Chance(0.5)) s.tone_hz = std::round(extra_rng_.Uniform(2500, 3200) / 10) * 10;
    sources_.push_back(s);
  }
  if (rooms_.size() > 1 && extra_rng_.Chance(o_.music_probability)) {
    const SiteRoom& r = rooms_[1 + extra_rng_.Int(0, static_cast<int>(rooms_.size()) - 2)];
    SoundSource s;
    s.name = "radio";
    s.kind = SourceKind::kMusic;
    s.position = {Mm(extra_rng_.Uniform(r.min.x() + 0.5, r.max.x() - 0.5)),
                  Mm(extra_rng_.Uniform(r.min.y() + 0.5, r.max.y() - 0.5)), 1.0};
    s.level_db_spl = std::round(extra_rng_.Uniform(55, 62));
    s.start_s = std::round(extra_rng_.Uniform(0, 20));
    s.every_s = std::round(extra_rng_.Uniform(30, 60));
    s.duration_s = std::round(extra_rng_.Uniform(10, 20));
    sources_.push_back(s);
  }
  for (const Item& it : items_) {
    if (it.hums) sources_.push_back(it.noise);
  }
}

void Builder::Finish(Site* site) {
  World& w = site->world;
  w = CurrentWorld(false);
  w.name = "site_" + std::to_string(o_.seed);
  for (size_t i = 0; i < people_.size(); ++i) {
    people_[i].id = static_cast<int>(i) + 1;
    people_[i].name = "person" + std::to_string(i + 1);
  }
  w.people = people_;
  AddSounds();
  for (size_t i = 0; i < sources_.size(); ++i) sources_[i].id = static_cast<int>(i) + 1;
  w.sources = sources_;
  const bool dark =
      o_.lighting == "dark" || (o_.lighting == "seed" && rng_.Chance(o_.dark_probability));
  w.lights_on = !dark;
  w.ceiling_height_m = height_;
  w.floor_colour = Vary(&rng_, 120, 118, 112, 15);
  w.ceiling_colour = Colour(228, 228, 225);
  // Sabine for the mean room: RT60 = 0.161 V / (S alpha), V = A h, S = 2 A + P h, with a mean
  // absorption alpha ~ U(0.18, 0.3) (plaster, a few soft furnishings, no acoustic ceiling).
  double area = 0, perimeter = 0;
  int n = 0;
  for (const SiteRoom& r : rooms_) {
    area += r.Area();
    perimeter += 2 * (r.max - r.min).sum();
    ++n;
  }
  area /= n;
  perimeter /= n;
  const double alpha = rng_.Uniform(0.18, 0.3);
  const double rt60 = 0.161 * area * height_ / ((2 * area + perimeter * height_) * alpha);
  w.acoustics.rt60_s = std::round(std::clamp(rt60, 0.25, 1.5) * 100) / 100;
  w.acoustics.ambient_noise_db_spl = std::round(rng_.Uniform(30, 40));
  site->rooms = rooms_;
  site->size_m = {length_, depth_};
  site->hidden_people.clear();
  for (int i : hidden_) site->hidden_people.push_back(i + 1);
}

bool Builder::Build(Site* site) {
  Layout();
  int rooms = 0;
  for (const SiteRoom& r : rooms_) rooms += !r.corridor;
  if (rooms < o_.min_rooms) return false;
  // Hidden people first: they need free corners.
  const int people = rng_.Int(o_.people_min, o_.people_max);
  const int hidden = std::min(people, rng_.Int(o_.hidden_min, o_.hidden_max));
  for (int h = 0, tries = 0; h < hidden; ++tries) {
    if (tries > 40) return false;
    h += PlaceHidden(PickRoom(false));
  }
  // Machines against walls, each humming.
  const int machines = rng_.Int(o_.machines_min, o_.machines_max);
  for (int m = 0, tries = 0; m < machines && tries < 40; ++tries) {
    Item item;
    item.kind = Item::kFurniture;
    item.box.name = "machine";
    const Eigen::Vector2d size(Cm(rng_.Uniform(0.8, 1.2)), Cm(rng_.Uniform(0.6, 0.8)));
    item.box.size_m = {size.x(), size.y(), Cm(rng_.Uniform(1.0, 1.6))};
    item.box.colour = Vary(&rng_, 90, 100, 110);
    if (!PlaceAgainstWall(PickRoom(false), item, size)) continue;
    Item& placed = items_.back();
    placed.hums = true;
    placed.noise.name = "machine" + std::to_string(++m);
    placed.noise.kind = SourceKind::kNoise;
    placed.noise.position = {placed.box.centre.x(), placed.box.centre.y(),
                             Cm(0.8 * placed.box.size_m.z())};
    placed.noise.level_db_spl = std::round(rng_.Uniform(50, 58));
    placed.noise.hum_hz = rng_.Chance(0.5) ? 50 : 60;
  }
  // Furniture per room.
  for (size_t r = 1; r < rooms_.size(); ++r) {
    const int count = rng_.Int(o_.furniture_min_per_room, o_.furniture_max_per_room) +
                      static_cast<int>(rooms_[r].Area() / 20.0);
    for (int k = 0; k < count; ++k) {
      const double u = rng_.Uniform();
      if (u < 0.25) {
        PlaceTable(static_cast<int>(r));
        continue;
      }
      Item item;
      item.kind = Item::kFurniture;
      Eigen::Vector3d size;
      if (u < 0.45) {
        item.box.name = "cabinet";
        size = {Cm(rng_.Uniform(0.8, 1.2)), Cm(rng_.Uniform(0.45, 0.6)),
                Cm(rng_.Uniform(1.7, 2.0))};
        item.box.colour = Vary(&rng_, 150, 150, 160);
      } else if (u < 0.65) {
        item.box.name = "shelf";
        size = {Cm(rng_.Uniform(1.0, 1.6)), Cm(rng_.Uniform(0.35, 0.45)),
                Cm(rng_.Uniform(1.6, 2.1))};
        item.box.colour = Vary(&rng_, 120, 90, 60);
      } else if (u < 0.75) {
        item.box.name = "bed";
        size = {Cm(rng_.Uniform(1.9, 2.1)), Cm(rng_.Uniform(0.9, 1.5)),
                Cm(rng_.Uniform(0.45, 0.6))};
        item.box.colour = Vary(&rng_, 170, 170, 190);
      } else if (u < 0.87) {
        item.box.name = "sofa";
        size = {Cm(rng_.Uniform(1.6, 2.2)), Cm(rng_.Uniform(0.8, 0.95)),
                Cm(rng_.Uniform(0.75, 0.9))};
        item.box.colour = Vary(&rng_, 90, 60, 60, 30);
      } else {
        item.box.name = "chair";
        size = {0.45, 0.45, Cm(rng_.Uniform(0.8, 1.0))};
        item.box.colour = Vary(&rng_, 40, 40, 90, 30);
      }
      item.box.size_m = size;
      PlaceAgainstWall(static_cast<int>(r), item, size.head<2>());
    }
  }
  const int debris = rng_.Int(o_.debris_min, o_.debris_max);
  for (int d = 0; d < debris; ++d) PlaceDebris();
  if (!Repair()) return false;
  if (!PlacePeople(people - hidden)) return false;
  Finish(site);
  return true;
}

}  // namespace

int Site::rooms_without_corridor() const {
  int n = 0;
  for (const SiteRoom& r : rooms) n += !r.corridor;
  return n;
}

Site GenerateSiteLayout(const SiteOptions& options) {
  common::ValidateOptions(options);
  for (int attempt = 0; attempt < options.max_attempts; ++attempt) {
    Site site;
    Builder builder(options,
                    Mix(Mix(static_cast<uint64_t>(options.seed)) + static_cast<uint64_t>(attempt)));
    if (builder.Build(&site)) {
      site.attempt = attempt;
      return site;
    }
  }
  throw std::runtime_error("no site passed the checks in " + std::to_string(options.max_attempts) +
                           " attempts (seed " + std::to_string(options.seed) +
                           "): too many rooms, people or hidden people for the floor area?");
}

World GenerateSite(const SiteOptions& options) { return GenerateSiteLayout(options).world; }

std::string SiteHeader(const SiteOptions& options) {
  std::ostringstream out;
  out << "# Generated incident site: sarmap-site --seed " << options.seed
      << " (components/sim/site_generator.cc).\n"
      << "# Reference: components/sim/WORLD_FORMAT.md. Generator options:\n";
  std::istringstream lines(common::OptionsToYaml(options, false));
  for (std::string line; std::getline(lines, line);) out << "#   " << line << "\n";
  return out.str();
}

std::string SiteSummary(const Site& site, double reachable_m2) {
  const World& w = site.world;
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(1);
  out << w.name << ": " << site.size_m.x() << " x " << site.size_m.y() << " m building, "
      << site.size_m.prod() << " m^2, " << site.rooms_without_corridor()
      << " rooms and a corridor, " << reachable_m2 << " m^2 reachable; walls " << w.ceiling_height_m
      << " m; " << (w.lights_on ? "lit" : "dark") << "; " << w.boxes.size() << " boxes, "
      << w.tables.size() << " tables; " << w.people.size() << " people (";
  for (size_t i = 0; i < w.people.size(); ++i) {
    const Person& p = w.people[i];
    const bool hidden = std::find(site.hidden_people.begin(), site.hidden_people.end(), p.id) !=
                        site.hidden_people.end();
    out << (i ? ", " : "") << p.name << " " << PostureName(p.posture) << (hidden ? " hidden" : "");
  }
  out << "); " << w.sources.size() << " sound sources (";
  for (size_t i = 0; i < w.sources.size(); ++i) {
    out << (i ? ", " : "") << w.sources[i].name;
    if (w.sources[i].kind != SourceKind::kVoice) out << " " << SourceKindName(w.sources[i].kind);
  }
  out << "); RT60 " << std::setprecision(2) << w.acoustics.rt60_s << " s.";
  return out.str();
}

}  // namespace sim
}  // namespace sarmap
