// The precompute cache (docs/model.md, "Start-up and the precompute cache"): a model read from it
// computes the same bits as one that built its pieces; a damaged, truncated, foreign or
// inconsistent entry is never trusted (rebuilt and replaced); other inputs miss; the folder keeps
// to its cap without touching files it did not write; concurrent builders leave one whole entry;
// the precompute on a thread pool gives the same bits as on one thread; the cache trusts only what
// the file system says is this user's alone (docs/model.md, "Who the cache trusts").
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

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

// The trust tests build many models: the smallest that has group pieces.
SensorOptions TinyOptions() {
  SensorOptions o = SmallOptions();
  o.clamps_per_edge = 3;
  o.elements_per_section = 1;
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
        ASSERT_TRUE(cache.Load(KeyOfEntry(entry), 1 << 20, [&](ByteReader& r) {
          return r.Vector<double>() == garbage;
        }));
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

mode_t ModeOf(const fs::path& path) {
  struct stat st {};
  EXPECT_EQ(::lstat(path.c_str(), &st), 0) << path;
  return st.st_mode & 07777;
}

std::string Bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Collects the untrusted-folder warnings of one test (the default goes to stderr).
class Warnings {
 public:
  Warnings() {
    SetUntrustedCacheWarning([this](const std::string& m) { messages_.push_back(m); });
  }
  ~Warnings() {
    SetUntrustedCacheWarning([](const std::string&) {});
  }
  Warnings(const Warnings&) = delete;
  Warnings& operator=(const Warnings&) = delete;
  const std::vector<std::string>& messages() const { return messages_; }

 private:
  std::vector<std::string> messages_;
};

TEST(PrecomputeCache, FoldersAreCreatedOwnerOnlyWhateverTheUmask) {
  TempFolder folder("precompute-cache");
  const mode_t old = ::umask(0);
  { const SensorModel model(TinyOptions(), CacheIn(folder.path() / "combabc" / "precompute")); }
  ::umask(old);
  EXPECT_EQ(ModeOf(folder.path() / "combabc"), 0700u);
  EXPECT_EQ(ModeOf(folder.path() / "combabc" / "precompute"), 0700u);
  const std::vector<fs::path> entries = Entries(folder.path() / "combabc" / "precompute");
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_EQ(ModeOf(entries[0]) & 077, 0u);
  // A folder that exists keeps its mode (the user chose it).
  EXPECT_EQ(ModeOf(folder.path()), 0777u & ~old);
}

// An entry others could have written (the review's attack: pieces swapped, checksum recomputed)
// is rebuilt and replaced by one of this user's.
TEST(PrecomputeCache, AnEntryOthersCanWriteIsRebuilt) {
  TempFolder folder("precompute-cache");
  const std::vector<double> reference = Profiles(SensorModel(TinyOptions()));
  { const SensorModel build(TinyOptions(), CacheIn(folder.path())); }
  const fs::path entry = Entries(folder.path()).at(0);
  ASSERT_EQ(::chmod(entry.c_str(), 0666), 0);
  const SensorModel rebuilt(TinyOptions(), CacheIn(folder.path()));
  EXPECT_FALSE(rebuilt.precompute_from_cache());
  EXPECT_EQ(Profiles(rebuilt), reference);
  EXPECT_EQ(ModeOf(entry) & 077, 0u);
  EXPECT_TRUE(SensorModel(TinyOptions(), CacheIn(folder.path())).precompute_from_cache());
  // Group-writable alone is enough.
  ASSERT_EQ(::chmod(entry.c_str(), 0620), 0);
  EXPECT_FALSE(SensorModel(TinyOptions(), CacheIn(folder.path())).precompute_from_cache());
}

// Only root can give a file away: the same as another user's entry in our folder.
TEST(PrecomputeCache, AnEntryOfAnotherUserIsRebuilt) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to give a file to another user";
  TempFolder folder("precompute-cache");
  { const SensorModel build(TinyOptions(), CacheIn(folder.path())); }
  const fs::path entry = Entries(folder.path()).at(0);
  ASSERT_EQ(::chown(entry.c_str(), 65534, 65534), 0);
  ASSERT_EQ(::chmod(entry.c_str(), 0600), 0);
  EXPECT_FALSE(SensorModel(TinyOptions(), CacheIn(folder.path())).precompute_from_cache());
  struct stat st {};
  ASSERT_EQ(::stat(entry.c_str(), &st), 0);
  EXPECT_EQ(st.st_uid, ::geteuid());  // replaced by ours
}

// A folder another user could write is not ours to keep: nothing read from it, nothing written
// or evicted there, one warning naming it.
TEST(PrecomputeCache, AFolderOthersCanWriteIsNotUsed) {
  TempFolder folder("precompute-cache");
  const fs::path cache = folder.path() / "shared";
  { const SensorModel build(TinyOptions(), CacheIn(cache)); }
  const fs::path entry = Entries(cache).at(0);
  const std::string planted = Bytes(entry);
  for (const mode_t mode : {0777, 0770}) {
    SCOPED_TRACE(mode);
    ASSERT_EQ(::chmod(cache.c_str(), mode), 0);
    Warnings warnings;
    SensorOptions other = TinyOptions();
    other.frequency_hz = 6.0;
    EXPECT_FALSE(SensorModel(TinyOptions(), CacheIn(cache)).precompute_from_cache());
    EXPECT_FALSE(SensorModel(other, CacheIn(cache)).precompute_from_cache());
    EXPECT_EQ(Entries(cache).size(), 1u);  // the other frequency was not stored
    EXPECT_EQ(Bytes(entry), planted);      // nor the entry replaced
    EXPECT_NE(UntrustedCacheFolder(cache.string()).find("writable by group or others"),
              std::string::npos);
  }
  // A folder on the way that others can write, without the sticky bit, is as bad.
  ASSERT_EQ(::chmod(cache.c_str(), 0700), 0);
  ASSERT_EQ(::chmod(folder.path().c_str(), 0777), 0);
  EXPECT_NE(UntrustedCacheFolder(cache.string()), "");
  ASSERT_EQ(::chmod(folder.path().c_str(), 01777), 0);  // as /tmp
  EXPECT_EQ(UntrustedCacheFolder(cache.string()), "");
  ASSERT_EQ(::chmod(folder.path().c_str(), 0755), 0);
  EXPECT_TRUE(SensorModel(TinyOptions(), CacheIn(cache)).precompute_from_cache());
}

TEST(PrecomputeCache, TheWarningNamesTheFolderOncePerProcess) {
  TempFolder folder("precompute-cache");
  const fs::path cache = folder.path() / "open";
  fs::create_directories(cache);
  ASSERT_EQ(::chmod(cache.c_str(), 0777), 0);
  Warnings warnings;
  { const SensorModel a(TinyOptions(), CacheIn(cache)); }
  { const SensorModel b(TinyOptions(), CacheIn(cache)); }
  ASSERT_EQ(warnings.messages().size(), 1u);
  EXPECT_NE(warnings.messages()[0].find(cache.string()), std::string::npos);
  EXPECT_NE(warnings.messages()[0].find("chmod go-w"), std::string::npos);
  EXPECT_TRUE(Entries(cache).empty());
}

TEST(PrecomputeCache, AFolderOfAnotherUserIsNotUsed) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to give a folder to another user";
  TempFolder folder("precompute-cache");
  const fs::path cache = folder.path() / "theirs";
  { const SensorModel build(TinyOptions(), CacheIn(cache)); }
  ASSERT_EQ(::chown(cache.c_str(), 65534, 65534), 0);
  Warnings warnings;
  EXPECT_FALSE(SensorModel(TinyOptions(), CacheIn(cache)).precompute_from_cache());
  EXPECT_NE(UntrustedCacheFolder(cache.string()).find("owned by user 65534"), std::string::npos);
}

// Planted files at an entry's name: none blocks, none is followed, none makes us allocate; each is
// a miss, and the entry is rebuilt in its place.
TEST(PrecomputeCache, PlantedFilesNeitherBlockNorBloat) {
  TempFolder folder("precompute-cache");
  { const SensorModel build(TinyOptions(), CacheIn(folder.path())); }
  const fs::path entry = Entries(folder.path()).at(0);
  const PrecomputeKey key = KeyOfEntry(entry);
  const std::string good = Bytes(entry);
  const auto plant_and_check = [&](const auto& plant, const std::string& what) {
    SCOPED_TRACE(what);
    fs::remove(entry);
    plant();
    const PrecomputeCache cache(folder.path().string(), 1 << 30);
    bool called = false;
    EXPECT_FALSE(cache.Load(key, good.size(), [&](ByteReader&) { return called = true; }));
    EXPECT_FALSE(called);  // refused before anything was read
    EXPECT_FALSE(SensorModel(TinyOptions(), CacheIn(folder.path())).precompute_from_cache());
    EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(entry)));
    EXPECT_TRUE(SensorModel(TinyOptions(), CacheIn(folder.path())).precompute_from_cache());
  };
  plant_and_check([&] { ASSERT_EQ(::mkfifo(entry.c_str(), 0600), 0); }, "a FIFO");
  const fs::path elsewhere = folder.path() / "elsewhere";
  std::ofstream(elsewhere, std::ios::binary) << good;
  plant_and_check([&] { fs::create_symlink(elsewhere, entry); }, "a link to a good entry");
  // A sparse file of 100 GB whose header claims it all: a size no model of these options needs.
  plant_and_check(
      [&] {
        std::ofstream(entry, std::ios::binary) << good.substr(0, 48);
        fs::resize_file(entry, std::uint64_t{100} << 30);
      },
      "a 100 GB sparse file");
}

// The bound on an entry's size (twice the estimated peak) is far above what real entries take:
// payload / estimate was 0.60 here (the tightest), 0.47 for the default sensor with one or two
// loads, 0.01 for the tiny one.
TEST(PrecomputeCache, RealEntriesFitTheirBound) {
  SensorOptions two_loads = SmallOptions();
  two_loads.load_cases.push_back(two_loads.load_cases[0]);
  two_loads.load_cases[1].load_x = 0.7;
  for (const SensorOptions& o : {SmallOptions(), two_loads}) {
    SCOPED_TRACE(o.clamps_per_edge);
    TempFolder folder("precompute-cache");
    { const SensorModel build(o, CacheIn(folder.path())); }
    const double payload = static_cast<double>(fs::file_size(Entries(folder.path()).at(0)) - 48);
    EXPECT_LT(payload, o.EstimatedMemoryBytes());
    EXPECT_TRUE(SensorModel(o, CacheIn(folder.path())).precompute_from_cache());
  }
}

TEST(PrecomputeCache, NoFolderNoCache) {
  const SensorModel model(SmallOptions(), PrecomputeOptions{});
  EXPECT_FALSE(model.precompute_from_cache());
}

}  // namespace
}  // namespace combabc::plate
