// MAT-files through libmatio (mat_file.hpp).
#include "io/mat_file.hpp"

#include <dlfcn.h>
#include <matio.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <type_traits>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"
#include "io/mat_structure.hpp"

namespace accelcal::internal {

namespace {

[[noreturn]] void Fail(const std::string& path, const std::string& why) {
  throw InputError(path, 0, VisibleLine(why));
}

// libmatio, loaded when the first MAT-file is read. Linked, it and what it links (HDF5, and
// through it curl, TLS, Kerberos: some 40 libraries) were loaded and relocated at the start of
// every run, a MAT-file read or not: 17 M instructions, most of a short command's.
struct MatioLibrary {
  decltype(&Mat_LogInitFunc) log_init = nullptr;
  decltype(&Mat_Open) open = nullptr;
  decltype(&Mat_Close) close = nullptr;
  decltype(&Mat_VarReadNextInfo) read_next_info = nullptr;
  decltype(&Mat_VarRead) read = nullptr;
  decltype(&Mat_VarFree) free = nullptr;
  std::string error;  ///< why it could not be loaded; empty when it was
};

// libmatio logs its errors through a function it calls; the library never prints, so they are
// kept here (the last one, per thread) for the error accelcal raises.
thread_local std::string last_matio_message;
void KeepMessage(int /*level*/, char* message) {
  last_matio_message = message != nullptr ? message : "";
}

const MatioLibrary& LoadedMatio() {
  static const MatioLibrary matio = [] {
    MatioLibrary m;
    void* library = dlopen(ACCELCAL_MATIO_SONAME, RTLD_NOW | RTLD_LOCAL);
    if (library == nullptr) {
      const char* why = dlerror();
      m.error = why != nullptr ? why : "not found";
      return m;
    }
    const auto bind = [&](auto* function, const char* name) {
      *function = reinterpret_cast<std::remove_pointer_t<decltype(function)>>(dlsym(library, name));
      if (*function == nullptr && m.error.empty()) m.error = std::string("it has no ") + name;
    };
    bind(&m.log_init, "Mat_LogInitFunc");
    bind(&m.open, "Mat_Open");
    bind(&m.close, "Mat_Close");
    bind(&m.read_next_info, "Mat_VarReadNextInfo");
    bind(&m.read, "Mat_VarRead");
    bind(&m.free, "Mat_VarFree");
    if (m.error.empty()) m.log_init("accelcal", KeepMessage);
    return m;
  }();
  return matio;
}

// libmatio for reading `path`; InputError when it cannot be loaded.
const MatioLibrary& MatioFor(const std::string& path) {
  const MatioLibrary& m = LoadedMatio();
  if (!m.error.empty()) {
    Fail(path, "reading a MAT-file needs libmatio (" ACCELCAL_MATIO_SONAME
               ", Debian's package libmatio" ACCELCAL_MATIO_MAJOR
               "), which could not be "
               "loaded: " +
                   m.error);
  }
  return m;
}

// A matrix with more columns than this and at most this many rows is stored turned.
constexpr std::size_t kMaxFields = 16;

const char* ClassName(matio_classes c) {
  switch (c) {
    case MAT_C_DOUBLE:
      return "double";
    case MAT_C_SINGLE:
      return "single";
    case MAT_C_INT8:
      return "int8";
    case MAT_C_UINT8:
      return "uint8";
    case MAT_C_INT16:
      return "int16";
    case MAT_C_UINT16:
      return "uint16";
    case MAT_C_INT32:
      return "int32";
    case MAT_C_UINT32:
      return "uint32";
    case MAT_C_INT64:
      return "int64";
    case MAT_C_UINT64:
      return "uint64";
    case MAT_C_CHAR:
      return "char";
    case MAT_C_STRUCT:
      return "struct";
    case MAT_C_CELL:
      return "cell";
    case MAT_C_SPARSE:
      return "sparse";
    case MAT_C_OBJECT:
      return "object";
    case MAT_C_FUNCTION:
      return "function";
    default:
      return "unknown";
  }
}

bool Numeric(const matvar_t& v) {
  switch (v.class_type) {
    case MAT_C_DOUBLE:
    case MAT_C_SINGLE:
    case MAT_C_INT8:
    case MAT_C_UINT8:
    case MAT_C_INT16:
    case MAT_C_UINT16:
    case MAT_C_INT32:
    case MAT_C_UINT32:
    case MAT_C_INT64:
    case MAT_C_UINT64:
      return v.rank == 2 && v.isComplex == 0 && v.isLogical == 0;
    default:
      return false;
  }
}

double ValueAt(const matvar_t& v, std::size_t i) {
  switch (v.class_type) {
    case MAT_C_DOUBLE:
      return static_cast<const double*>(v.data)[i];
    case MAT_C_SINGLE:
      return static_cast<const float*>(v.data)[i];
    case MAT_C_INT8:
      return static_cast<const std::int8_t*>(v.data)[i];
    case MAT_C_UINT8:
      return static_cast<const std::uint8_t*>(v.data)[i];
    case MAT_C_INT16:
      return static_cast<const std::int16_t*>(v.data)[i];
    case MAT_C_UINT16:
      return static_cast<const std::uint16_t*>(v.data)[i];
    case MAT_C_INT32:
      return static_cast<const std::int32_t*>(v.data)[i];
    case MAT_C_UINT32:
      return static_cast<const std::uint32_t*>(v.data)[i];
    case MAT_C_INT64:
      return static_cast<double>(static_cast<const std::int64_t*>(v.data)[i]);
    case MAT_C_UINT64:
      return static_cast<double>(static_cast<const std::uint64_t*>(v.data)[i]);
    default:
      return 0;
  }
}

std::size_t SizeOfClass(matio_classes c) {
  switch (c) {
    case MAT_C_DOUBLE:
    case MAT_C_INT64:
    case MAT_C_UINT64:
      return 8;
    case MAT_C_SINGLE:
    case MAT_C_INT32:
    case MAT_C_UINT32:
      return 4;
    case MAT_C_INT16:
    case MAT_C_UINT16:
      return 2;
    default:
      return 1;
  }
}

// Only ever made once libmatio is loaded (MatioFor).
struct CloseMat {
  void operator()(mat_t* m) const { LoadedMatio().close(m); }
};
struct FreeVar {
  void operator()(matvar_t* v) const { LoadedMatio().free(v); }
};
using MatFile = std::unique_ptr<mat_t, CloseMat>;
using MatVar = std::unique_ptr<matvar_t, FreeVar>;

std::string Matio() {
  return last_matio_message.empty() ? std::string() : " (libmatio: " + last_matio_message + ")";
}

MatFile Open(const std::string& path) {
  const MatioLibrary& matio = MatioFor(path);
  last_matio_message.clear();
  MatFile mat(matio.open(path.c_str(), MAT_ACC_RDONLY));
  if (!mat) Fail(path, "a MAT-file libmatio cannot open" + Matio());
  return mat;
}

MatVariable Describe(const matvar_t& v) {
  MatVariable out;
  out.name = v.name != nullptr ? v.name : "";
  out.type = ClassName(v.class_type);
  if (v.isComplex != 0) out.type = "complex " + out.type;
  if (v.isLogical != 0) out.type = "logical";
  for (int d = 0; d < v.rank && v.dims != nullptr; ++d) out.dims.push_back(v.dims[d]);
  out.numeric_matrix = Numeric(v);
  return out;
}

std::string Shape(const MatVariable& v) {
  std::string out;
  for (std::size_t d : v.dims) out += (out.empty() ? "" : "x") + std::to_string(d);
  return out + " " + v.type;
}

}  // namespace

double MatTable::At(std::size_t row, std::size_t column) const {
  const auto& v = *static_cast<const matvar_t*>(data.get());
  // MATLAB stores a matrix column after column: a turned one's samples are its columns.
  return transposed ? ValueAt(v, row * columns + column) : ValueAt(v, column * rows + row);
}

bool IsMatFile(std::string_view first_bytes) {
  return first_bytes.substr(0, 16) == "MATLAB 5.0 MAT-f" ||
         first_bytes.substr(0, 16) == "MATLAB 7.3 MAT-f";
}

std::vector<MatVariable> ListMatVariables(const std::string& path) {
  if (const std::optional<std::string> why = CheckMatStructure(path)) {
    Fail(path, "a MAT-file that is corrupt or cut short: " + *why);
  }
  const MatFile mat = Open(path);
  std::vector<MatVariable> out;
  while (true) {
    last_matio_message.clear();
    const MatVar v(LoadedMatio().read_next_info(mat.get()));
    if (!v) break;
    out.push_back(Describe(*v));
  }
  if (!last_matio_message.empty()) Fail(path, "a MAT-file libmatio cannot read" + Matio());
  return out;
}

MatTable ReadMatTable(const std::string& path, const std::string& name) {
  const std::vector<MatVariable> all = ListMatVariables(path);
  std::string list;
  for (const MatVariable& v : all)
    list += (list.empty() ? "" : ", ") + v.name + " (" + Shape(v) + ")";
  if (list.empty()) list = "none";
  std::string chosen = name;
  if (chosen.empty()) {
    std::vector<const MatVariable*> numeric;
    for (const MatVariable& v : all) {
      if (v.numeric_matrix) numeric.push_back(&v);
    }
    if (numeric.size() != 1) {
      Fail(path, (numeric.empty() ? "no numeric matrix among its variables: " + list
                                  : "several numeric matrices: " + list +
                                        "; choose one with the topic option (its name)"));
    }
    chosen = numeric.front()->name;
  }
  if (chosen.empty()) {
    // libmatio gives a variable whose name element is malformed (not text) or empty the name "",
    // under which it cannot find it again.
    Fail(path,
         "its numeric matrix has no name (the variable's name element is empty or not "
         "text): a MAT-file's variable is read by its name");
  }
  const auto it =
      std::find_if(all.begin(), all.end(), [&](const MatVariable& v) { return v.name == chosen; });
  if (it == all.end()) Fail(path, "no variable " + chosen + " (its variables: " + list + ")");
  if (!it->numeric_matrix) {
    Fail(path, "the variable " + chosen + " is " + Shape(*it) +
                   ", not a real numeric matrix (rows of samples)");
  }
  const std::size_t rows = it->dims[0], columns = it->dims[1];
  if (rows == 0 || columns == 0) {
    Fail(path, "the variable " + chosen + " is " + Shape(*it) + ": it holds no values");
  }
  if (rows != 0 && columns > kMaxMatValues / rows) {
    Fail(path, Format("the variable %s has %zu x %zu values, more than the %zu accelcal reads "
                      "from a MAT-file (8.4 M samples of time,x,y,z; a longer session can be "
                      "read as text)",
                      chosen.c_str(), rows, columns, kMaxMatValues));
  }
  const MatFile mat = Open(path);
  last_matio_message.clear();
  std::shared_ptr<matvar_t> v(LoadedMatio().read(mat.get(), chosen.c_str()), FreeVar());
  if (!v || v->data == nullptr || !Numeric(*v) || v->dims[0] != rows || v->dims[1] != columns ||
      v->nbytes < rows * columns * SizeOfClass(v->class_type)) {
    Fail(path, "the variable " + chosen + " cannot be read" + Matio());
  }
  MatTable out;
  out.variable = chosen;
  out.transposed = columns > kMaxFields && rows <= kMaxFields;
  out.rows = out.transposed ? columns : rows;
  out.columns = out.transposed ? rows : columns;
  out.data = std::move(v);
  return out;
}

}  // namespace accelcal::internal
