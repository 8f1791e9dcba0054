#include "wire/names.hpp"

namespace shadow::names {
namespace {

using v1::Filter;
using v1::Light;

constexpr Row<Technique, v1::Technique> kTechniqueRows[] = {
    {Technique::kUniform, v1::TECHNIQUE_UNIFORM, "uniform"},
    {Technique::kPsm, v1::TECHNIQUE_PSM, "psm"},
    {Technique::kCube, v1::TECHNIQUE_CUBE, "cube"},
    {Technique::kPsmCube, v1::TECHNIQUE_PSM_CUBE, "psm_cube"},
    {Technique::kLispsm, v1::TECHNIQUE_LISPSM, "lispsm"},
    {Technique::kAuto, v1::TECHNIQUE_AUTO, "auto"},
    {Technique::kVirtual, v1::TECHNIQUE_VIRTUAL, "virtual"},
};

constexpr Row<PsmCasters, v1::PsmCasterMode> kPsmCastersRows[] = {
    {PsmCasters::kInverseProjection, v1::PSM_CASTERS_INVERSE_PROJECTION, "inverse-projection"},
    {PsmCasters::kSlideBack, v1::PSM_CASTERS_SLIDE_BACK, "slide-back"},
};

constexpr Row<MapFit, v1::MapFit> kMapFitRows[] = {
    {MapFit::kView, v1::MAP_FIT_VIEW, "view"},
    {MapFit::kScene, v1::MAP_FIT_SCENE, "scene"},
};

constexpr Row<PsmNear, v1::PsmNearMode> kPsmNearRows[] = {
    {PsmNear::kReceivers, v1::PSM_NEAR_RECEIVERS, "receivers"},
    {PsmNear::kCamera, v1::PSM_NEAR_CAMERA, "camera"},
    {PsmNear::kVirtualSlideBack, v1::PSM_NEAR_VIRTUAL_SLIDE_BACK, "virtual-slide-back"},
};

constexpr Row<LightType, Light::KindCase> kLightTypeRows[] = {
    {LightType::kDirectional, Light::kDirectional, "directional"},
    {LightType::kSpot, Light::kSpot, "spot"},
    {LightType::kPoint, Light::kPoint, "point"},
};

constexpr Row<FilterKind, Filter::KindCase> kFilterKindRows[] = {
    {FilterKind::kHard, Filter::kHard, "hard"},
    {FilterKind::kPcf2x2, Filter::kPcf2X2, "pcf2x2"},
    {FilterKind::kPoisson, Filter::kPoisson, "poisson"},
    {FilterKind::kPcss, Filter::kPcss, "pcss"},
    {FilterKind::kBlur, Filter::kBlur, "blur"},
    {FilterKind::kCsm, Filter::kCsm, "csm"},
    {FilterKind::kPcssCsm, Filter::kPcssCsm, "pcss_csm"},
    {FilterKind::kAtlasSat, Filter::kAtlasSat, "atlas_sat"},
    {FilterKind::kAtlasMip, Filter::kAtlasMip, "atlas_mip"},
};

constexpr Row<CsmStorage, v1::CsmStorage> kCsmStorageRows[] = {
    {CsmStorage::kFloat32, v1::CSM_STORAGE_FLOAT32, "float32"},
    {CsmStorage::kFloat16, v1::CSM_STORAGE_FLOAT16, "float16"},
};

constexpr Row<CsmLookup, v1::CsmLookup> kCsmLookupRows[] = {
    {CsmLookup::kMips, v1::CSM_LOOKUP_MIPS, "mips"},
    {CsmLookup::kSat, v1::CSM_LOOKUP_SAT, "sat"},
};

constexpr Row<Product, v1::Product> kProductRows[] = {
    {Product::kShadowMap, v1::PRODUCT_SHADOW_MAP, "shadowmap", "shadow_map"},
    {Product::kVisibility, v1::PRODUCT_VISIBILITY, "visibility"},
    {Product::kPosition, v1::PRODUCT_POSITION, "position"},
    {Product::kTexelDensity, v1::PRODUCT_TEXEL_DENSITY, "texel_density"},
    {Product::kShadowMapMips, v1::PRODUCT_SHADOW_MAP_MIPS, "shadowmap_mips"},
    {Product::kShadowMapSat, v1::PRODUCT_SHADOW_MAP_SAT, "shadowmap_sat"},
    {Product::kVisibilityMips, v1::PRODUCT_VISIBILITY_MIPS, "visibility_mips"},
    {Product::kVisibilitySat, v1::PRODUCT_VISIBILITY_SAT, "visibility_sat"},
    {Product::kCsmBasis, v1::PRODUCT_CSM_BASIS, "csm_basis"},
    {Product::kBlockerDepth, v1::PRODUCT_BLOCKER_DEPTH, "blocker_depth"},
    {Product::kShadowAtlas, v1::PRODUCT_SHADOW_ATLAS, "shadow_atlas"},
    {Product::kShadowAtlasMips, v1::PRODUCT_SHADOW_ATLAS_MIPS, "shadow_atlas_mips"},
    {Product::kShadowAtlasSat, v1::PRODUCT_SHADOW_ATLAS_SAT, "shadow_atlas_sat"},
    {Product::kAtlasUvs, v1::PRODUCT_ATLAS_UVS, "atlas_uvs"},
    {Product::kVirtualPages, v1::PRODUCT_VIRTUAL_PAGES, "virtual_pages"},
};

constexpr Row<PixelFormat, v1::PixelFormat> kPixelFormatRows[] = {
    {PixelFormat::kFloat32, v1::PIXEL_FORMAT_FLOAT32, "float32"},
    {PixelFormat::kFloat64, v1::PIXEL_FORMAT_FLOAT64, "float64"},
    {PixelFormat::kFloat16, v1::PIXEL_FORMAT_FLOAT16, "float16"},
};

constexpr Row<ChunkCompression, v1::ChunkCompression> kChunkCompressionRows[] = {
    {ChunkCompression::kNone, v1::CHUNK_COMPRESSION_NONE, "none"},
    {ChunkCompression::kZstd, v1::CHUNK_COMPRESSION_ZSTD, "zstd"},
};

}  // namespace

// "mode" for both PSM settings: "unknown mode 'x'" next to the flag or field that names them.
constinit const Table<Technique, v1::Technique> kTechniques{"technique", kTechniqueRows};
constinit const Table<PsmCasters, v1::PsmCasterMode> kPsmCasters{"mode", kPsmCastersRows};
constinit const Table<PsmNear, v1::PsmNearMode> kPsmNear{"mode", kPsmNearRows};
constinit const Table<MapFit, v1::MapFit> kMapFits{"map fit", kMapFitRows};
constinit const Table<LightType, Light::KindCase> kLightTypes{"light kind", kLightTypeRows};
constinit const Table<FilterKind, Filter::KindCase> kFilterKinds{"filter", kFilterKindRows};
constinit const Table<CsmStorage, v1::CsmStorage> kCsmStorages{"storage", kCsmStorageRows};
constinit const Table<CsmLookup, v1::CsmLookup> kCsmLookups{"lookup", kCsmLookupRows};
constinit const Table<Product, v1::Product> kProducts{"product", kProductRows};
constinit const Table<PixelFormat, v1::PixelFormat> kPixelFormats{"pixel format", kPixelFormatRows};
constinit const Table<ChunkCompression, v1::ChunkCompression> kChunkCompressions{
    "chunk compression", kChunkCompressionRows};

}  // namespace shadow::names
