// The .fot format: bit-identical round trips, and a clear error for every damaged or hostile file.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <thread>

#include <sys/stat.h>
#include <unistd.h>
#include <boost/crc.hpp>

#include <pcl_fot/io/fot_file.h>
#include <pcl_fot/pcl/cloud_insertion.h>

#include "scan_data.h"

using namespace pcl::fot;

namespace {

/** room_scan1 ray-traced at 5 cm: free space in collapsed regions of many sizes, and occupied walls. */
const FastOctTree& realMap() {
  return pcl_fot_test::perScanSet<FastOctTree>([] {
    FastOctTree t(0.05);
    insertScan(t, *pcl_fot_test::loadScan("room_scan1.pcd"));
    return t;
  });
}

std::string tempPath(const std::string& name) {
  return ::testing::TempDir() + "pcl_fot_" + std::to_string(::getpid()) + "_" + name;
}

void put32(std::string& bytes, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) bytes[at + i] = char((v >> (8 * i)) & 0xFF);
}
void put64(std::string& bytes, std::size_t at, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) bytes[at + i] = char((v >> (8 * i)) & 0xFF);
}
void putDouble(std::string& bytes, std::size_t at, double v) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, 8);
  put64(bytes, at, bits);
}
/** Recomputes the trailing CRC, so that a deliberate change reaches the checks behind it. */
void reseal(std::string& bytes) {
  boost::crc_32_type crc;
  crc.process_bytes(bytes.data(), bytes.size() - 4);
  put32(bytes, bytes.size() - 4, crc.checksum());
}

/** Decodes `bytes`, expecting a FormatError whose message contains `why`. */
void expectRejected(const std::string& bytes, const std::string& why) {
  try {
    io::decodeFot(bytes.data(), bytes.size(), "test.fot");
    ADD_FAILURE() << "accepted a file that should fail with: " << why;
  } catch (const io::FormatError& e) {
    EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("test.fot"), std::string::npos) << "the message names the file";
  }
}

}  // namespace

PCL_FOT_SCAN_TESTS(FotFileOnScans);

TEST_P(FotFileOnScans, RoundTripIsBitIdentical) {
  const FastOctTree& map = realMap();
  ASSERT_GT(map.getFreeCount(), 0u);
  const std::string bytes = io::encodeFot(map);
  const FastOctTree back = io::decodeFot(bytes.data(), bytes.size());
  EXPECT_TRUE(back == map);
  EXPECT_EQ(back.getGrid(), map.getGrid());
  EXPECT_EQ(io::encodeFot(back), bytes);

  const std::string path = tempPath("round_trip.fot");
  io::saveFot(map, path);
  io::saveFot(map, path);  // over an existing file
  const FastOctTree loaded = io::loadFot(path);
  EXPECT_TRUE(loaded == map);
  EXPECT_EQ(io::encodeFot(loaded), bytes);
  std::remove(path.c_str());
}

TEST(FotFile, GridAndEmptyMapsSurvive) {
  FastOctTree odd(0.037, 0.123456789, -17.5, 1e-9);
  odd.setCell({-3, 4, 1000}, CellState::Free);
  const std::string bytes = io::encodeFot(odd);
  const FastOctTree back = io::decodeFot(bytes.data(), bytes.size());
  EXPECT_TRUE(back == odd);
  EXPECT_EQ(back.getResolution(), 0.037);
  EXPECT_EQ(back.getGrid().origin()[0], 0.123456789);
  const FastOctTree empty(0.2);
  const std::string e = io::encodeFot(empty);
  EXPECT_EQ(e.size(), 152u + 32u + 4u);
  EXPECT_TRUE(io::decodeFot(e.data(), e.size()).empty());
}

// test/data/map_v1.fot was written by the version-1 encoder, whose nodes sat 0x2AAA cells off today's.
TEST(FotFile, VersionOneFilesLoadIntoTodaysNodes) {
  FastOctTree expected(0.1);
  for (int i = 0; i < 50; ++i) expected.setCell({i % 7, i / 7, i % 3}, CellState::Occupied);
  expected.setBox({-20, -5, 3}, {17, 9, 40}, CellState::Free);
  for (int i = 0; i < 20; ++i) expected.setCell({-i * 3, 2 * i, -i}, CellState::Occupied);
  const FastOctTree loaded = io::loadFot(std::string(PCL_FOT_SOURCE_DIR) + "/test/data/map_v1.fot");
  EXPECT_EQ(loaded, expected);
  EXPECT_EQ(loaded.getFreeCount(), 21660u);
  const std::string again = io::encodeFot(loaded);
  EXPECT_EQ(again[8], char(io::kFotVersion)) << "saving writes today's version";
  EXPECT_EQ(io::decodeFot(again.data(), again.size()), expected);
  // Within the caller's cap, like any file.
  EXPECT_THROW(io::loadFot(std::string(PCL_FOT_SOURCE_DIR) + "/test/data/map_v1.fot", 12 * 1024),
               MemoryLimitError);
}

TEST(FotFile, EveryHeaderFieldIsChecked) {
  FastOctTree small(0.1);
  for (int i = 0; i < 50; ++i) small.setCell({i % 7, i / 7, i % 3}, CellState::Occupied);
  const std::string good = io::encodeFot(small);
  std::string b;

  expectRejected("", "magic");
  expectRejected(good.substr(0, 40), "ends inside the header");
  b = good;
  b[1] = 'X';
  expectRejected(b, "magic");
  b = good;
  put32(b, 8, 4);
  expectRejected(b, "version 4");
  b = good;
  put32(b, 12, 128);
  expectRejected(b, "header of 128 bytes");
  b = good;
  put64(b, 16, 0);
  reseal(b);
  expectRejected(b, "resolution");
  putDouble(b, 16, 1e300);  // finite, but its cell centres are not floats
  reseal(b);
  expectRejected(b, "float's range");
  b = good;
  putDouble(b, 24, std::nan(""));
  reseal(b);
  expectRejected(b, "origin");
  b = good;
  put64(b, 72, std::uint64_t(1) << 40);
  expectRejected(b, "blocks");
  b = good;
  put64(b, 64, 5);
  expectRejected(b, "node count");
  b = good;
  put64(b, 72, std::uint64_t(1) << 30);  // 32 GiB claimed: refused by size, nothing allocated
  put64(b, 64, 1 + 8 * (std::uint64_t(1) << 30));
  expectRejected(b, "cap");
  b = good;
  b.pop_back();
  expectRejected(b, "truncated");
  b = good + "x";
  expectRejected(b, "trailing bytes");
  b = good;
  b[200] ^= 0x40;
  expectRejected(b, "checksum");
  b = good;
  put64(b, 80, small.getOccupiedCount() + 1);
  reseal(b);
  expectRejected(b, "cell counts");
  b = good;
  put32(b, 48, 0);
  reseal(b);
  expectRejected(b, "root level");
  b = good;
  put32(b, 152 + 4 * 9, 0x10u | node::uniform(CellState::Free));  // a spare bit in a pool word
  reseal(b);
  expectRejected(b, "spare bits");
  b = good;
  put32(b, 96, 2);
  reseal(b);
  expectRejected(b, "update rule 2");
  b = good;
  putDouble(b, 120, 0.9);  // clamp_min above the threshold
  reseal(b);
  expectRejected(b, "clamps");
  b = good;
  put64(b, 144, 1);
  expectRejected(b, "truncated");
  EXPECT_THROW(io::decodeFot(good.data(), good.size(), "test.fot", 64), io::FormatError)
      << "the caller's cap";
}

/** A map of three scans by the log-odds rule: most leaves carry values. */
FastOctTree logOddsMap() {
  FastOctTree t(0.1);
  t.setUpdateRule(UpdateRule::LogOdds);
  t.setSensorModel(SensorModel(0.75, 0.35));
  const auto cloud = pcl_fot_test::loadScan("room_scan2.pcd");
  for (int i = 0; i < 3; ++i) insertScan(t, *cloud);
  return t;
}

TEST_P(FotFileOnScans, LogOddsRuleModelAndValuesRoundTrip) {
  const FastOctTree map = logOddsMap();
  ASSERT_GT(map.getUnsettledCount(), 10000u);
  const std::string bytes = io::encodeFot(map);
  const FastOctTree back = io::decodeFot(bytes.data(), bytes.size());
  EXPECT_TRUE(back == map);
  EXPECT_EQ(back.getUpdateRule(), UpdateRule::LogOdds);
  EXPECT_EQ(back.getSensorModel(), SensorModel(0.75, 0.35));
  EXPECT_EQ(back.getUnsettledCount(), map.getUnsettledCount());
  EXPECT_EQ(io::encodeFot(back), bytes);
}

TEST(FotFile, DamagedValuesAreRefused) {
  FastOctTree t(0.1);
  t.updateLogOdds(Key{0, 0, 0}, 0.5f);  // one leaf, the root, with one value and seven unknown cells
  const std::string good = io::encodeFot(t);
  ASSERT_EQ(good.size(), 152u + 32u + 32u + 4u);
  const std::size_t values = 152 + 32;
  std::string b = good;
  putDouble(b, values + 4, 0.0);  // a value for an unknown cell
  reseal(b);
  expectRejected(b, "known");
  b = good;
  put32(b, values, 0xBF000000u);  // -0.5: thresholded free, where the word says occupied
  reseal(b);
  expectRejected(b, "thresholded");
  b = good;
  float max = SensorModel().clampMaxLogOdds();
  std::uint32_t max_bits;
  std::memcpy(&max_bits, &max, 4);
  put32(b, values, max_bits);  // settled: a leaf with no value between the clamps needs no flag
  reseal(b);
  expectRejected(b, "between the clamps");
  b = good;
  put32(b, values, 0x7F800000u);  // +Inf
  reseal(b);
  expectRejected(b, "infinite");
}

TEST(FotFile, FilesOfVersionTwoLoadAsBinaryMaps) {
  std::string v2;
  {
    std::ifstream in(std::string(PCL_FOT_SOURCE_DIR) + "/fuzz/corpus/fot_loader/small.fot", std::ios::binary);
    v2.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_EQ(v2[8], 2) << "a file made before version 3";
  const FastOctTree t = io::decodeFot(v2.data(), v2.size());
  EXPECT_GT(t.getOccupiedCount(), 0u);
  EXPECT_EQ(t.getUpdateRule(), UpdateRule::Binary);
  EXPECT_EQ(t.getSensorModel(), SensorModel());
  EXPECT_EQ(t.getUnsettledCount(), 0u);
  const std::string v3 = io::encodeFot(t);
  EXPECT_TRUE(io::decodeFot(v3.data(), v3.size()) == t);
}

TEST_P(FotFileOnScans, ThousandsOfDamagedFilesFailCleanlyOrLoadValidMaps) {
  const std::string good = io::encodeFot(realMap());
  std::mt19937 rng(2007);
  int refused = 0, loaded = 0;
  auto attempt = [&](const std::string& bytes) {
    try {
      const FastOctTree t = io::decodeFot(bytes.data(), bytes.size(), "damaged.fot");
      // Whatever loads is a valid canonical map: it encodes back to exactly the bytes it came from.
      EXPECT_EQ(io::encodeFot(t), bytes);
      ++loaded;
    } catch (const io::FormatError&) {
      ++refused;
    }
  };
  for (int i = 0; i < 400; ++i) attempt(good.substr(0, rng() % good.size()));  // truncated
  for (int i = 0; i < 400; ++i) {                                              // bit flips
    std::string b = good;
    for (unsigned n = 1 + rng() % 4; n > 0; --n) b[rng() % b.size()] ^= char(1u << (rng() % 8));
    attempt(b);
  }
  for (int i = 0; i < 400;
       ++i) {  // flips in the header or pool behind a valid checksum: hostile, not damaged
    std::string b = good;
    const std::size_t at = rng() % 2 ? 8 + rng() % 144 : 152 + rng() % (b.size() - 156);
    b[at] ^= char(1u << (rng() % 8));
    reseal(b);
    attempt(b);
  }
  EXPECT_EQ(refused + loaded, 1200);
  EXPECT_GT(refused, 1050);  // a flip in a sensor model's mantissa may leave a valid model
}

TEST(FotFile, FilesThatCannotBeReadOrAreHuge) {
  EXPECT_THROW(io::loadFot(tempPath("missing.fot")), std::runtime_error);
  const std::string path = tempPath("huge.fot");
  {
    FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    ASSERT_EQ(::ftruncate(fileno(f), (off_t(5) << 30) + 100), 0);  // sparse: takes no disk
    std::fclose(f);
  }
  EXPECT_THROW(io::loadFot(path), io::FormatError) << "refused by its size, before reading";
  std::remove(path.c_str());

  // What has no size to check: a directory, a device without end, a FIFO no one writes (opening it for
  // reading would wait for a writer).
  const std::string fifo = tempPath("fifo.fot");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const std::string& odd : {std::string("/tmp"), std::string("/dev/zero"), fifo}) {
    try {
      io::loadFot(odd);
      ADD_FAILURE() << odd << " loaded";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("is not a regular file"), std::string::npos) << e.what();
    }
  }
  std::remove(fifo.c_str());
}

TEST(FotFile, SavesAreAtomicEvenFromThreadsSavingOnePath) {
  // Four maps of different sizes, saved over one path from four threads at once: the file is always one of
  // them whole, and no temporary file is left behind.
  std::vector<FastOctTree> maps;
  for (int m = 0; m < 4; ++m) {
    maps.emplace_back(0.1);
    for (int i = 0; i < 200 * (m + 1); ++i) maps.back().setCell({i % 37, i / 37, m}, CellState::Occupied);
  }
  const std::string dir = tempPath("atomic_dir");
  std::filesystem::create_directory(dir);
  const std::string path = dir + "/map.fot";
  std::vector<std::thread> savers;
  std::atomic<int> failures{0};
  for (int m = 0; m < 4; ++m)
    savers.emplace_back([&, m] {
      for (int round = 0; round < 25; ++round) try {
          io::saveFot(maps[std::size_t(m)], path);
        } catch (const std::exception&) {
          ++failures;
        }
    });
  for (auto& t : savers) t.join();
  EXPECT_EQ(failures.load(), 0);
  const FastOctTree saved = io::loadFot(path);
  EXPECT_TRUE(std::any_of(maps.begin(), maps.end(), [&](const FastOctTree& m) { return m == saved; }));
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) files += entry.is_regular_file();
  EXPECT_EQ(files, 1u) << "a temporary file was left behind";
  // A save that cannot be made leaves nothing either.
  EXPECT_THROW(io::saveFot(maps[0], dir + "/missing/map.fot"), std::runtime_error);
  std::filesystem::remove_all(dir);
}
