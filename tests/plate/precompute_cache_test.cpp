// The precompute cache (docs/model.md, "Start-up and the precompute cache"): a model read from it
// computes the same bits as one that built its pieces; a damaged, truncated, foreign or
// inconsistent entry is never trusted (rebuilt and replaced); other inputs miss; the folder keeps
// to its cap without touching files it did not write; concurrent builders leave one whole entry;
// the precompute on a thread pool gives the same bits as on one thread.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "combabc/core/thread_pool.hpp"
#include "combabc/plate/sensor_model.hpp"
#include "plate/fast_path/precompute_cache.hpp"
#include "plate_test_support.hpp"
#include "support/test_support.hpp"

namespace combabc::plate {
namespace {

namespace fs = std::filesystem;

using combabc::testing::TempFolder;

SensorOptions SmallOptions() {
  SensorOptions o;
  o.elements_per_section = 2;
  o.elements_across_width = 2;
  return o;
}

PrecomputeOptions CacheIn(const fs::path& folder, std::uint64_t max_bytes = 1 << 30) {
  PrecomputeOptions p;
  p.cache_directory = folder.string();
  p.cache_max_bytes = max_bytes;
  return p;
}

// The profiles of a fixed set of configurations, bit for bit comparable.
std::vector<double> Profiles(const SensorModel& model) {
  std::mt19937_64 rng(7);
  std::vector<double> all;
  std::vector<double> out(static_cast<std::size_t>(model.num_outputs()));
  for (int k = 0; k < 12; ++k) {
    model.Profile(testing::RandomClamps(rng, model.num_clamps()), out);
    all.insert(all.end(), out.begin(), out.end());
  }
  return all;
}

std::vector<fs::path> Entries(const fs::path& folder) {
  std::vector<fs::path> entries;
  for (const auto& e : fs::directory_iterator(folder)) {
    if (e.path().extension() == ".precompute") entries.push_back(e.path());
  }
  return entries;
}

PrecomputeKey KeyOfEntry(const fs::path& entry) {
  const std::string name = entry.stem().string();
  return {std::stoull(name.substr(0, 16), nullptr, 16), std::stoull(name.substr(16), nullptr, 16)};
}

TEST(PrecomputeCache, AModelReadFromTheCacheComputesTheSameBits) {
  TempFolder folder("precompute-cache");
  const std::vector<double> reference = Profiles(SensorModel(SmallOptions()));
  const SensorModel first(SmallOptions(), CacheIn(folder.path()));
  EXPECT_FALSE(first.precompute_from_cache());
  ASSERT_EQ(Entries(folder.path()).size(), 1u);
  const SensorModel second(SmallOptions(), CacheIn(folder.path()));
  EXPECT_TRUE(second.precompute_from_cache());
  EXPECT_EQ(Profiles(first), reference);
  EXPECT_EQ(Profiles(second), reference);
  EXPECT_EQ(second.fast_path_certified(), first.fast_path_certified());
  EXPECT_EQ(second.PrecomputedBytes(), first.PrecomputedBytes());
}

TEST(PrecomputeCache, OtherInputsMiss) {
  TempFolder folder("precompute-cache");
  const SensorModel first(SmallOptions(), CacheIn(folder.path()));
  SensorOptions other = SmallOptions();
  other.frequency_hz = 6.0;
  EXPECT_FALSE(SensorModel(other, CacheIn(folder.path())).precompute_from_cache());
  other = SmallOptions();
  other.load_cases[0].load_x = 0.7;
  EXPECT_FALSE(SensorModel(other, CacheIn(folder.path())).precompute_from_cache());
  other = SmallOptions();
  other.layers[1].youngs_modulus *= 1.01;
  EXPECT_FALSE(SensorModel(other, CacheIn(folder.path())).precompute_from_cache());
  EXPECT_EQ(Entries(folder.path()).size(), 4u);
  // The output scale is applied after the solve: normalising or not shares the entry.
  other = SmallOptions();
  other.normalise = false;
  EXPECT_TRUE(SensorModel(other, CacheIn(folder.path())).precompute_from_cache());
}

// Each damage is detected, the model is rebuilt with the same bits, and the entry is replaced by a
// good one (the next model reads it).
TEST(PrecomputeCache, ADamagedEntryIsRebuiltNeverTrusted) {
  TempFolder folder("precompute-cache");
  const std::vector<double> reference = Profiles(SensorModel(SmallOptions()));
  const auto damage_and_check = [&](const auto& damage, const std::string& what) {
    SCOPED_TRACE(what);
    { const SensorModel build(SmallOptions(), CacheIn(folder.path())); }
    const std::vector<fs::path> entries = Entries(folder.path());
    ASSERT_EQ(entries.size(), 1u);
    damage(entries[0]);
    const SensorModel rebuilt(SmallOptions(), CacheIn(folder.path()));
    EXPECT_FALSE(rebuilt.precompute_from_cache());
    EXPECT_EQ(Profiles(rebuilt), reference);
    const SensorModel again(SmallOptions(), CacheIn(folder.path()));
    EXPECT_TRUE(again.precompute_from_cache());
    EXPECT_EQ(Profiles(again), reference);
  };
  damage_and_check(
      [](const fs::path& entry) {
        std::fstream f(entry, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(static_cast<std::streamoff>(fs::file_size(entry) / 2));
        const char byte = 0x5a;
        f.write(&byte, 1);
      },
      "a byte of the payload changed");
  damage_and_check([](const fs::path& entry) { fs::resize_file(entry, fs::file_size(entry) - 8); },
                   "truncated");
  damage_and_check(
      [](const fs::path& entry) { std::ofstream(entry, std::ios::binary) << "not an entry"; },
      "replaced by another file");
  // A payload with a valid header and checksum that does not describe a condensation.
  damage_and_check(
      [&](const fs::path& entry) {
        const PrecomputeCache cache(folder.path().string(), 1 << 30);
        const std::vector<double> garbage(512, 3.0);
        ASSERT_TRUE(cache.Store(KeyOfEntry(entry), [&](ByteWriter& w) { w.Vector(garbage); }));
        // A reader that takes the bytes for what they are finds them whole.
        ASSERT_TRUE(cache.Load(KeyOfEntry(entry),
                               [&](ByteReader& r) { return r.Vector<double>() == garbage; }));
      },
      "a consistent file of inconsistent content");
}

TEST(PrecomputeCache, TheFolderKeepsToItsCapAndToItsOwnFiles) {
  TempFolder folder("precompute-cache");
  const fs::path foreign = folder.path() / "notes.txt";
  std::ofstream(foreign) << "the user's file";
  const fs::path look_alike = folder.path() / "0123.precompute";  // not a name the cache writes
  std::ofstream(look_alike) << "x";
  const auto cache_entries = [&] {
    std::vector<fs::path> entries = Entries(folder.path());
    std::erase(entries, look_alike);
    return entries;
  };
  { const SensorModel first(SmallOptions(), CacheIn(folder.path())); }
  ASSERT_EQ(cache_entries().size(), 1u);
  const std::uint64_t one = fs::file_size(cache_entries()[0]);
  // Room for one entry: each new one pushes out the least recently used.
  SensorOptions other = SmallOptions();
  other.frequency_hz = 6.0;
  { const SensorModel second(other, CacheIn(folder.path(), one + one / 2)); }
  EXPECT_EQ(cache_entries().size(), 1u);
  EXPECT_TRUE(fs::exists(foreign));
  EXPECT_TRUE(fs::exists(look_alike));
  EXPECT_TRUE(SensorModel(other, CacheIn(folder.path())).precompute_from_cache());
  EXPECT_FALSE(
      SensorModel(SmallOptions(), CacheIn(folder.path(), one + one / 2)).precompute_from_cache());
}

TEST(PrecomputeCache, ConcurrentBuildersLeaveOneWholeEntry) {
  TempFolder folder("precompute-cache");
  const std::vector<double> reference = Profiles(SensorModel(SmallOptions()));
  std::vector<std::vector<double>> results(4);
  std::vector<std::thread> builders;
  for (std::size_t k = 0; k < results.size(); ++k) {
    builders.emplace_back(
        [&, k] { results[k] = Profiles(SensorModel(SmallOptions(), CacheIn(folder.path()))); });
  }
  for (std::thread& t : builders) t.join();
  for (const std::vector<double>& r : results) EXPECT_EQ(r, reference);
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(folder.path())) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 1u);  // no temporary left behind
  EXPECT_TRUE(SensorModel(SmallOptions(), CacheIn(folder.path())).precompute_from_cache());
}

TEST(PrecomputeCache, ThePrecomputeOnAThreadPoolGivesTheSameBits) {
  ThreadPool pool(3);
  PrecomputeOptions threads;
  threads.pool = &pool;
  EXPECT_EQ(Profiles(SensorModel(SmallOptions(), threads)), Profiles(SensorModel(SmallOptions())));
}

TEST(PrecomputeCache, NoFolderNoCache) {
  const SensorModel model(SmallOptions(), PrecomputeOptions{});
  EXPECT_FALSE(model.precompute_from_cache());
}

}  // namespace
}  // namespace combabc::plate
