#include <catch2/catch.hpp>

#include <sstream>

#include "kg/retime/playback.hpp"

using namespace kg;

namespace {

motion::Motion ramp(int frames, double fps) {
  auto skeleton = std::make_shared<motion::Skeleton>();
  skeleton->add_joint(
      {.name = "root",
       .channels = {{.kind = motion::ChannelKind::Xposition}, {.kind = motion::ChannelKind::Zrotation}}});
  motion::Motion m{skeleton, motion::FrameMatrix::Zero(frames, 2), fps, "ramp"};
  for (int f = 0; f < frames; ++f) m.values(f, 0) = f * 0.1, m.values(f, 1) = 0.01 * f;
  return m;
}

}  // namespace

TEST_CASE("playing a clip through a uniform warp at double speed keeps every other frame") {
  const motion::Motion source = ramp(61, 30);  // 2 s
  const retime::TimeWarp warp = retime::TimeWarp::uniform(2.0, 1.0, 10);
  const motion::Motion out = retime::retimed_motion(source, warp, 30);
  REQUIRE(out.frame_count() == 31);
  for (int k = 0; k < 31; ++k) {
    CHECK(out.values(k, 0) == Approx(source.values(2 * k, 0)).margin(1e-9));
    CHECK(out.values(k, 1) == Approx(source.values(2 * k, 1)).margin(1e-9));
  }
  CHECK(out.fps == 30);
}

TEST_CASE("a warp for another clip's duration is refused, curves are written per output frame") {
  const motion::Motion source = ramp(61, 30);
  CHECK_THROWS_WITH(retime::retimed_motion(source, retime::TimeWarp::uniform(3.0, 1.0, 10), 30),
                    Catch::Matchers::Contains("lasts 2"));
  std::ostringstream csv, json;
  const retime::TimeWarp warp = retime::TimeWarp::uniform(2.0, 1.0, 10);
  retime::write_warp_csv(csv, warp, 10);
  std::string line;
  std::istringstream lines(csv.str());
  int rows = 0;
  std::getline(lines, line);
  CHECK(line == "t,p,pdot,pddot");
  while (std::getline(lines, line)) ++rows;
  CHECK(rows == 11);
  retime::write_warp_json(json, warp, 10);
  CHECK_THAT(json.str(), Catch::Matchers::Contains("\"pdot\":[2"));
}

TEST_CASE("output_frame_count is the frames written at the output rate, and refuses counts beyond reach") {
  const retime::TimeWarp warp = retime::TimeWarp::uniform(2.0, 1.0, 10);
  CHECK(retime::output_frame_count(warp, 30) == 31);
  CHECK(retime::output_frame_count(warp, 24) == 25);
  CHECK(retime::output_frame_count(warp, 7.5) == 8);
  CHECK(retime::retimed_motion(ramp(61, 30), warp, 24).frame_count() == retime::output_frame_count(warp, 24));
  CHECK_THROWS_WITH(retime::output_frame_count(warp, 0),
                    Catch::Matchers::Contains("retimed playback: fps 0 (expected > 0)"));
  const retime::TimeWarp long_warp = retime::TimeWarp::uniform(2.0, 1e4, 10);
  CHECK_THROWS_WITH(retime::output_frame_count(long_warp, 1e5),
                    "retimed playback: 10000 s at fps 100000 is 1e+09 frames (expected at most 10000000)");
}

TEST_CASE("a clip that outlasts the warp's source by its slack plays its tail at the warp's end speed") {
  // 2.1 s of clip, a warp of its first 2 s at double speed: the last 0.1 s plays at 2x too.
  const motion::Motion source = ramp(64, 30);
  const retime::TimeWarp warp = retime::TimeWarp::uniform(2.0, 1.0, 10);
  CHECK(retime::played_duration(warp, source.duration()) == Approx(1.05));
  CHECK(retime::played_duration(warp, 1.9) == 1.0);  // no tail: the warp's duration
  const retime::WarpSample past = retime::played_sample(warp, 1.04);
  CHECK(past.p == Approx(2.08));
  CHECK(past.pdot == Approx(2));
  CHECK(past.pddot == 0);
  const motion::Motion out = retime::retimed_motion(source, warp, 60, 0.1);
  REQUIRE(out.frame_count() == 64);  // floor(1.05 * 60) + 1: every source frame, to the last
  for (int k = 0; k < 64; ++k) CHECK(out.values(k, 0) == Approx(source.values(k, 0)).margin(1e-9));
  std::ostringstream csv;
  retime::write_warp_csv(csv, warp, 60, out.frame_count());
  std::istringstream lines(csv.str());
  std::string line, last;
  int rows = -1;
  while (std::getline(lines, line)) ++rows, last = line;
  CHECK(rows == 64);
  CHECK(last.rfind("1.05,2.1,2,0", 0) == 0);
}
