#include "studies/sqlite_statement.hpp"

#include "studies/store.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace gapflow::sqlite {

[[noreturn]] void fail(sqlite3* db, const std::string& what) {
  if (!db) throw std::runtime_error("results store: out of memory");
  const int code = sqlite3_errcode(db) & 0xff;
  const char* file = sqlite3_db_filename(db, "main");
  if (code == SQLITE_CORRUPT || code == SQLITE_NOTADB)
    throw StoreError(fmt::format("results store {} is damaged or not a results store: {}", file ? file : "?",
                                 sqlite3_errmsg(db)));
  throw std::runtime_error(fmt::format("results store {}: {}: {}", file ? file : "?", what, sqlite3_errmsg(db)));
}

}  // namespace gapflow::sqlite
