// The step kernels' C source as text (model/kernels/pzk.h lists the files, in order; the build
// embeds them byte for byte), for the headers `piezoid export` writes.
#pragma once

#include <string>
#include <string_view>

namespace pz::pzk {

/// The kernels' C source, in model/kernels/pzk.h's include order.
std::string KernelSource();
/// The include guard of the kernels in an exported header: PZK_KERNELS_ and a 64-bit hash of
/// KernelSource() in hex (headers exported from the same kernels share them).
std::string KernelGuard();
/// The bimorph fin's modal helpers (model/kernels/fin_modal.h): also the base of the HGANN fin
/// plant's header (controller/export_fin_c.h).
std::string FinModalSource();
/// The PZK_* name of a block kind, from the kernels' table of kinds (model/kernels/chain.h
/// pzk_kinds, one entry per id of common.h's enum); "0" for none.
std::string KindName(int kind);

}  // namespace pz::pzk
