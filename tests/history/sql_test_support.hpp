// SQL run on a history file by hand, as a user or an attacker would: the tests that change a
// history behind combabc's back (integrity, CLI checks) share it.
#pragma once

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <string>

namespace combabc::testing {

// Runs `sql` on the SQLite file at `path`; a failure is a test failure naming the statement.
inline void Sql(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  char* message = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message);
  const std::string text = message ? message : "";
  sqlite3_free(message);
  sqlite3_close(db);
  ASSERT_EQ(rc, SQLITE_OK) << sql << ": " << text;
}

}  // namespace combabc::testing
