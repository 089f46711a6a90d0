// Checks of a SQLite database's write-ahead log made from its bytes,
// before SQLite opens the database. SQLite ignores a log whose header is
// damaged and stops reading at the first damaged frame, so that whatever
// was committed after the damage is dropped without a word.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace yarf {

// Why the log at `wal` would lose committed transactions: its header is
// damaged while frames follow it, or a damaged frame has committed
// transactions of the same log after it. nullopt when it is sound, absent,
// or damaged only after its last commit: that is what a crash in the
// middle of writing a transaction leaves, and no commit of it was
// acknowledged. Throws Error when it cannot be read.
std::optional<std::string> WalDamage(const std::filesystem::path& wal);

// Whether the database file's header says it is in WAL mode.
bool InWalMode(const std::filesystem::path& database);

}  // namespace yarf
