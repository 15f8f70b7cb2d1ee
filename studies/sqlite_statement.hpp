// The results store's SQLite plumbing (internal to studies/store.cpp): errors that name the
// file, prepared statements bound by position, and a transaction rolled back unless committed.
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <optional>
#include <string>

namespace gapflow::sqlite {

// A damaged or foreign file is bad input (exit 2) and names the file; anything else
// (a full disk, a lock held for longer than the busy timeout) is a failure while running.
[[noreturn]] void fail(sqlite3* db, const std::string& what);

inline void exec(sqlite3* db, const char* sql) {
  if (sqlite3_exec(db, sql, nullptr, nullptr, nullptr) != SQLITE_OK) fail(db, sql);
}

// A prepared statement; bind() takes 1-based positions like SQLite.
class Statement {
 public:
  Statement(sqlite3* db, const char* sql) : db_(db) {
    if (sqlite3_prepare_v2(db, sql, -1, &s_, nullptr) != SQLITE_OK) fail(db, sql);
  }
  ~Statement() { sqlite3_finalize(s_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  Statement& bind(int i, const std::string& v) {
    return check(sqlite3_bind_text(s_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
  }
  Statement& bind(int i, std::int64_t v) { return check(sqlite3_bind_int64(s_, i, v)); }
  Statement& bind(int i, int v) { return check(sqlite3_bind_int64(s_, i, v)); }
  Statement& bind(int i, bool v) { return check(sqlite3_bind_int64(s_, i, v ? 1 : 0)); }
  Statement& bind(int i, double v) { return check(sqlite3_bind_double(s_, i, v)); }
  template <class T>
  Statement& bind(int i, const std::optional<T>& v) {
    return v ? bind(i, *v) : check(sqlite3_bind_null(s_, i));
  }

  // Bind every argument in order to ?1, ?2, ...
  template <class... A>
  Statement& bind_all(const A&... a) {
    int i = 0;
    (bind(++i, a), ...);  // a comma fold is evaluated left to right
    return *this;
  }

  // True while a row is available.
  bool step() {
    int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW) return true;
    if (rc != SQLITE_DONE) fail(db_, sqlite3_sql(s_));
    return false;
  }
  void run() {
    step();
    reset();
  }
  void reset() {
    sqlite3_reset(s_);
    sqlite3_clear_bindings(s_);
  }

  int columns() const { return sqlite3_column_count(s_); }
  std::string name(int c) const { return sqlite3_column_name(s_, c); }
  int type(int c) const { return sqlite3_column_type(s_, c); }
  std::string text(int c) const {
    auto p = reinterpret_cast<const char*>(sqlite3_column_text(s_, c));
    return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(s_, c))) : std::string();
  }
  std::int64_t int64(int c) const { return sqlite3_column_int64(s_, c); }
  int integer(int c) const { return static_cast<int>(sqlite3_column_int64(s_, c)); }
  double real(int c) const { return sqlite3_column_double(s_, c); }
  std::optional<double> optional_real(int c) const {
    if (type(c) == SQLITE_NULL) return std::nullopt;
    return real(c);
  }
  std::optional<bool> optional_bool(int c) const {
    if (type(c) == SQLITE_NULL) return std::nullopt;
    return integer(c) != 0;
  }

 private:
  Statement& check(int rc) {
    if (rc != SQLITE_OK) fail(db_, "bind");
    return *this;
  }
  sqlite3* db_;
  sqlite3_stmt* s_ = nullptr;
};

inline bool has_table(sqlite3* db, const std::string& name) {
  Statement s(db, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?");
  s.bind(1, name);
  return s.step();
}

inline bool has_column(sqlite3* db, const std::string& table, const std::string& column) {
  Statement s(db, "SELECT 1 FROM pragma_table_info(?) WHERE name = ?");
  s.bind_all(table, column);
  return s.step();
}

// The transaction of put(): rolled back unless commit() was reached.
class Transaction {
 public:
  explicit Transaction(sqlite3* db) : db_(db) { exec(db_, "BEGIN IMMEDIATE"); }
  ~Transaction() {
    if (!done_) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
  void commit() {
    exec(db_, "COMMIT");
    done_ = true;
  }

 private:
  sqlite3* db_;
  bool done_ = false;
};

}  // namespace gapflow::sqlite
