// NRRD with a detached header: part 1 of the input is image.nhdr, the following parts are the data
// files data1.raw, data2.raw, … beside it, and part 2 is also data.raw (the seeds name them with
// `data file: data.raw`, `data file: data%d.raw 1 N 1` and `data file: LIST`). The data files a
// dataset's checksum covers (nrrdDataFiles) lie in the header's folder, and a header that loads
// can be checksummed: its data files are listed without error.
#include "fuzz_image.h"
#include "volume/nrrd_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  auto& scratch = fuzz::Scratch::instance();
  scratch.fresh();
  const auto parts = fuzz::splitParts(data, size, 5);
  const auto path = scratch.write("image.nhdr", parts[0]).string();
  for (std::size_t i = 1; i < parts.size(); ++i) scratch.write("data" + std::to_string(i) + ".raw", parts[i]);
  if (parts.size() > 1) scratch.write("data.raw", parts[1]);
  const bool loaded = fuzz::checkLoaded(loadNrrd(path, fuzz::loaderOptions()), path);
  const auto files = nrrdDataFiles(path, fuzz::loaderOptions());
  fuzz::checkResult(files, path);
  if (loaded) fuzz::expect(bool(files), "a header that loads lists its data files");
  if (files) {
    std::error_code ec;
    const auto folder = std::filesystem::weakly_canonical(std::filesystem::path(path).parent_path(), ec);
    for (const std::string& file : *files) {
      const auto resolved = std::filesystem::weakly_canonical(file, ec);
      fuzz::expect(resolved.parent_path() == folder || resolved.string().rfind(folder.string() + "/", 0) == 0,
                   "a data file lies in the header's folder");
    }
  }
  return 0;
}
