#pragma once
// Atomic file replacement: the new contents go to "<path>.tmp.<pid>" in the same directory,
// are fsync'ed, then rename(2) moves them over <path>. Rename within one file system is
// atomic, so a reader (or a run killed mid-write) sees either the old file or the complete
// new one, never a truncated file under the final name. Because the data are on disk before
// the rename, a power loss keeps the old file or the new one as well; the directory itself
// is not fsync'ed, so the rename may be lost, never half-applied.
#include <functional>
#include <string>

namespace perishell::io {

// "<path>.tmp.<pid>": unique per process, so two runs writing one directory do not collide.
std::string temporaryPathFor(const std::string& path);

// Calls writeTemporary(temporaryPath), which must create and close the complete file there
// (any writer: HDF5, streams, ...), then fsyncs it and renames it over `path`. If
// writeTemporary throws, or fsync/rename fail, the temporary is removed, `path` is left as
// it was, and the exception propagates (OS failures as std::runtime_error naming the path
// and the errno text).
void replaceFileAtomically(const std::string& path,
                           const std::function<void(const std::string& temporaryPath)>& writeTemporary);

// Text (or any bytes) through replaceFileAtomically.
void writeFileAtomically(const std::string& path, const std::string& contents);

// Replaces the existing file's bytes from `offset` to its end, `previousTail`, by `newTail`
// in one write and fdatasyncs it: an append that keeps a file's closing text (the .xmf's
// closing tags) at its end, at the cost of the new text rather than of the whole file. If the
// write fails the file is cut back to `offset` and `previousTail` written again, and the
// error propagates as std::runtime_error naming the path and the errno text. Not atomic
// against a crash in the write itself (a torn tail), which replaceFileAtomically is.
void replaceFileTail(const std::string& path, std::size_t offset, const std::string& previousTail,
                     const std::string& newTail);

}  // namespace perishell::io
