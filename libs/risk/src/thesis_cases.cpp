#include "fleet/risk/thesis_cases.hpp"

#include <cmath>
#include <functional>
#include <numbers>

namespace fleet::risk {
namespace {

using Path = std::function<Disc(double t)>;

AlignedSource sample(const Path& path, int T, SourceKind kind = SourceKind::kRobot) {
  AlignedSource s{kind, {}};
  for (int t = 0; t <= T; ++t) {
    s.steps.emplace_back(path(static_cast<double>(t)));
  }
  return s;
}

GridSpec thesisGrid(double xmax, int N) {
  const double h = xmax / N;
  return GridSpec{-h / 2.0, -h / 2.0, h, N + 1, N + 1};
}

}  // namespace

std::vector<ThesisCase> thesisCases() {
  constexpr double kPi = std::numbers::pi;
  std::vector<ThesisCase> out;
  // Table 3.1 case 1: K = 10, R1 = 50, R2 = 30, T = 80, N = 80. Crossing at right angles; the small
  // disc passes through the centre of the large one at t = 40 (containment: p = (30/50)² = 0.36).
  out.push_back(
      {"table3_1_case1",
       "window 400x400; O1 r=50 from (40,200) to (360,200); O2 r=30 from (200,40) to (200,360); t=0..80",
       {10},
       false,
       thesisGrid(400, 80),
       {sample(
            [](double t) {
              return Disc{40 + 4 * t, 200, 50, 0};
            },
            80),
        sample(
            [](double t) {
              return Disc{200, 40 + 4 * t, 30, 0};
            },
            80)}});
  // Case 2: K = 10, R1 = R2 = 30, T = 50, N = 50. The two diagonals; the discs coincide at t = 25 (p = 1).
  out.push_back(
      {"table3_1_case2",
       "window 300x300; O1 r=30 from (30,30) to (270,270); O2 r=30 from (270,30) to (30,270); t=0..50",
       {10},
       false,
       thesisGrid(300, 50),
       {sample(
            [](double t) {
              return Disc{30 + 4.8 * t, 30 + 4.8 * t, 30, 0};
            },
            50),
        sample(
            [](double t) {
              return Disc{270 - 4.8 * t, 30 + 4.8 * t, 30, 0};
            },
            50)}});
  // Case 3: K = 5 and 20, R1 = 50, R2 = 60, T = 100, N = 100. An arc against a straight line.
  out.push_back(
      {"table3_1_case3",
       "window 500x500; O1 r=50 on the upper half circle centre (250,150) radius 180 from angle pi to 0; "
       "O2 r=60 from (0,250) to (500,250); t=0..100",
       {5, 20},
       false,
       thesisGrid(500, 100),
       {sample(
            [=](double t) {
              const double a = kPi * (1.0 - t / 100.0);
              return Disc{250 + 180 * std::cos(a), 150 + 180 * std::sin(a), 50, 0};
            },
            100),
        sample(
            [](double t) {
              return Disc{5 * t, 250, 60, 0};
            },
            100)}});
  // Case 4: K = 5, 10, 15, 20 with case 3's sizes: a sinusoid against a line in the opposite direction.
  out.push_back(
      {"table3_1_case4",
       "window 500x500; O1 r=50 on y = 250 + 100 sin(2 pi t/100), x = 5t; O2 r=60 from (500,250) to "
       "(0,250); t=0..100",
       {5, 10, 15, 20},
       false,
       thesisGrid(500, 100),
       {sample(
            [=](double t) {
              return Disc{5 * t, 250 + 100 * std::sin(2 * kPi * t / 100), 50, 0};
            },
            100),
        sample(
            [](double t) {
              return Disc{500 - 5 * t, 250, 60, 0};
            },
            100)}});
  // Table 3.2 case 1: K = 5, R1 = 20, R2 = 30, T = 30, N = 30, shown as 1 − P.
  out.push_back(
      {"table3_2_case1",
       "window 150x150; O1 r=20 from (10,75) to (145,75); O2 r=30 from (75,10) to (75,145); t=0..30",
       {5},
       true,
       thesisGrid(150, 30),
       {sample(
            [](double t) {
              return Disc{10 + 4.5 * t, 75, 20, 0};
            },
            30),
        sample(
            [](double t) {
              return Disc{75, 10 + 4.5 * t, 30, 0};
            },
            30)}});
  // Table 3.2 case 2: K = 10, R1 = 50, R2 = 60, T = 100, N = 100, shown as 1 − P.
  out.push_back(
      {"table3_2_case2",
       "window 500x500; O1 r=50 from (50,50) to (450,450); O2 r=60 from (450,50) to (50,450); t=0..100",
       {10},
       true,
       thesisGrid(500, 100),
       {sample(
            [](double t) {
              return Disc{50 + 4 * t, 50 + 4 * t, 50, 0};
            },
            100),
        sample(
            [](double t) {
              return Disc{450 - 4 * t, 50 + 4 * t, 60, 0};
            },
            100)}});
  // Fig. 3.10: 1 − P with several obstacles (superposition): a robot crossing four moving obstacles.
  {
    ThesisCase c{
        "fig3_10_many",
        "window 500x500, K=10; robot r=40 from (20,250) to (480,250); obstacles r=30..50 on lines and "
        "a circle crossing its path; t=0..100",
        {10},
        true,
        thesisGrid(500, 100),
        {}};
    c.sources.push_back(sample([](double t) { return Disc{20 + 4.6 * t, 250, 40, 0}; }, 100));
    c.sources.push_back(sample(
        [](double t) {
          return Disc{120, 480 - 4 * t, 35, 0};
        },
        100, SourceKind::kHuman));
    c.sources.push_back(sample(
        [](double t) {
          return Disc{260, 20 + 4.6 * t, 50, 0};
        },
        100, SourceKind::kHuman));
    c.sources.push_back(sample([](double t) { return Disc{480 - 3 * t, 100 + 3 * t, 30, 0}; }, 100));
    c.sources.push_back(sample(
        [=](double t) {
          const double a = 2 * kPi * t / 100;
          return Disc{380 + 90 * std::cos(a), 250 + 90 * std::sin(a), 40, 0};
        },
        100, SourceKind::kHuman));
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace fleet::risk
