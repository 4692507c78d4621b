#include "Reference.h"

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cone.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include "rastercheck/model/Kinematics.h"

namespace rastercheck::test
{
bool bruteForceCollides(const CollisionModel &model, const double *q, double padding)
{
    if (!model.configurationAdmissible(q))
        return true;
    RobotData data(*model.robot);
    forwardKinematics(*model.robot, data, q);
    const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
    // The meshes of curved primitives lie outside the exact shapes: a pair they call colliding is
    // decided on the shapes, as in safe and exact mode (CurvedSolids).
    auto confirmed = [&](std::uint32_t pair, const Eigen::Isometry3d &poseA, const Eigen::Isometry3d &poseB)
    {
        return !model.curved.refines(pair) ||
               model.curved.collide(model, pair, toDevicePose(poseA), toDevicePose(poseB), padding);
    };
    const std::size_t m = model.numComponents();
    for (std::size_t c = 0; c < m; ++c)
    {
        const Eigen::Isometry3d &pose = data.oMl[model.componentLink[c]];
        for (std::size_t o = 0; o < model.numObjects(); ++o)
            if (solidsOverlap(*model.componentBvhs[c], pose, model.components[c].closed, *model.objectBvhs[o], identity,
                              model.objects[o].closed, padding) &&
                confirmed(device::environmentPair(static_cast<int>(o), static_cast<int>(c), static_cast<int>(m)), pose,
                          identity))
                return true;
    }
    for (std::size_t i = 0; i < model.selfPairs.size(); ++i)
    {
        const auto [a, b] = model.selfPairs[i];
        const Eigen::Isometry3d &poseA = data.oMl[model.componentLink[a]], &poseB = data.oMl[model.componentLink[b]];
        if (solidsOverlap(*model.componentBvhs[a], poseA, model.components[a].closed, *model.componentBvhs[b], poseB,
                          model.components[b].closed, padding) &&
            confirmed(device::selfPair(static_cast<int>(i), static_cast<int>(model.numObjects()), static_cast<int>(m)),
                      poseA, poseB))
            return true;
    }
    return false;
}

namespace
{
using Model = fcl::BVHModel<fcl::OBBRSSd>;

std::shared_ptr<Model> toFcl(const Mesh &mesh)
{
    auto model = std::make_shared<Model>();
    std::vector<fcl::Vector3d> vertices(mesh.vertices.begin(), mesh.vertices.end());
    std::vector<fcl::Triangle> triangles;
    for (const Mesh::Triangle &t : mesh.triangles)
        triangles.emplace_back(t[0], t[1], t[2]);
    model->beginModel();
    model->addSubModel(vertices, triangles);
    model->endModel();
    return model;
}

struct CollideData
{
    fcl::CollisionRequestd request;
    fcl::CollisionResultd result;
    bool done = false;
};

bool collideCallback(fcl::CollisionObjectd *a, fcl::CollisionObjectd *b, void *raw)
{
    auto *data = static_cast<CollideData *>(raw);
    if (data->done)
        return true;
    fcl::collide(a, b, data->request, data->result);
    data->done = data->result.isCollision();
    return data->done;
}

struct DistanceData
{
    double padding;
    bool done = false;
};

bool distanceCallback(fcl::CollisionObjectd *a, fcl::CollisionObjectd *b, void *raw, double &distance)
{
    auto *data = static_cast<DistanceData *>(raw);
    fcl::DistanceRequestd request;
    fcl::DistanceResultd result;
    fcl::distance(a, b, request, result);
    distance = result.min_distance;
    data->done = data->done || result.min_distance <= data->padding;
    return data->done;
}
}  // namespace

std::shared_ptr<fcl::CollisionGeometryd> toFcl(const PrimitiveShape &shape)
{
    switch (shape.kind)
    {
        case PrimitiveShape::Kind::Box:
            return std::make_shared<fcl::Boxd>(shape.size);
        case PrimitiveShape::Kind::Sphere:
            return std::make_shared<fcl::Sphered>(shape.size.x());
        case PrimitiveShape::Kind::Cylinder:
            return std::make_shared<fcl::Cylinderd>(shape.size.x(), shape.size.y());
        case PrimitiveShape::Kind::Cone:
            return std::make_shared<fcl::Coned>(shape.size.x(), shape.size.y());
    }
    return nullptr;
}

/** \brief FCL's objects for a model: its components (each with its geometry's frame in the link
    frame) and its scene objects, placed. With \a exactPrimitives a part made of one primitive is
    that primitive, else its mesh. */
struct FclObjects
{
    const CollisionModel &model;
    RobotData data;
    std::vector<std::unique_ptr<fcl::CollisionObjectd>> components;
    std::vector<Eigen::Isometry3d> componentOffsets;  // the FCL geometry's frame in the link frame
    std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;

    FclObjects(const CollisionModel &m, bool exactPrimitives) : model(m), data(*m.robot)
    {
        for (const Component &component : m.robot->components)
        {
            const bool primitive = exactPrimitives && component.shapes.size() == 1;
            components.push_back(std::make_unique<fcl::CollisionObjectd>(primitive ? toFcl(component.shapes[0])
                                                                                   : toFcl(component.mesh)));
            componentOffsets.push_back(primitive ? component.shapes[0].pose : Eigen::Isometry3d::Identity());
        }
        for (const SceneObject &object : m.scene->objects)
        {
            const bool primitive = exactPrimitives && object.shapes.size() == 1;
            objects.push_back(
                std::make_unique<fcl::CollisionObjectd>(primitive ? toFcl(object.shapes[0]) : toFcl(object.mesh)));
            if (primitive)
                objects.back()->setTransform(object.shapes[0].pose);
        }
    }
};

struct FclReference::Impl : FclObjects
{
    fcl::DynamicAABBTreeCollisionManagerd manager;

    Impl(const CollisionModel &m, bool exactPrimitives) : FclObjects(m, exactPrimitives)
    {
        for (const std::unique_ptr<fcl::CollisionObjectd> &object : objects)
        {
            object->computeAABB();
            manager.registerObject(object.get());
        }
        manager.setup();
    }
};

FclReference::FclReference(const CollisionModel &model, bool exactPrimitives)
    : impl_(std::make_unique<Impl>(model, exactPrimitives))
{
}

FclReference::~FclReference() = default;

bool FclReference::collides(const double *q, double padding)
{
    const CollisionModel &model = impl_->model;
    if (!model.configurationAdmissible(q))
        return true;
    forwardKinematics(*model.robot, impl_->data, q);
    for (std::size_t c = 0; c < impl_->components.size(); ++c)
    {
        const Eigen::Isometry3d pose = impl_->data.oMl[model.componentLink[c]] * impl_->componentOffsets[c];
        impl_->components[c]->setTransform(pose.linear(), pose.translation());
        impl_->components[c]->computeAABB();
    }
    for (auto &component : impl_->components)
    {
        if (padding > 0)
        {
            DistanceData data{padding};
            impl_->manager.distance(component.get(), &data, distanceCallback);
            if (data.done)
                return true;
        }
        else
        {
            CollideData data;
            impl_->manager.collide(component.get(), &data, collideCallback);
            if (data.done)
                return true;
        }
    }
    for (const auto &[a, b] : model.selfPairs)
    {
        fcl::CollisionObjectd *oa = impl_->components[a].get(), *ob = impl_->components[b].get();
        if (padding > 0)
        {
            fcl::DistanceRequestd request;
            fcl::DistanceResultd result;
            fcl::distance(oa, ob, request, result);
            if (result.min_distance <= padding)
                return true;
        }
        else
        {
            fcl::CollisionRequestd request;
            fcl::CollisionResultd result;
            if (fcl::collide(oa, ob, request, result) > 0)
                return true;
        }
    }
    return false;
}

struct FclDistance::Impl : FclObjects
{
    using FclObjects::FclObjects;
};

FclDistance::FclDistance(const CollisionModel &model, bool exactPrimitives)
    : impl_(std::make_unique<Impl>(model, exactPrimitives))
{
}

FclDistance::~FclDistance() = default;

double FclDistance::distance(const double *q, bool environment, bool self, Eigen::Vector3d *points)
{
    const CollisionModel &model = impl_->model;
    forwardKinematics(*model.robot, impl_->data, q);
    for (std::size_t c = 0; c < impl_->components.size(); ++c)
    {
        const Eigen::Isometry3d pose = impl_->data.oMl[model.componentLink[c]] * impl_->componentOffsets[c];
        impl_->components[c]->setTransform(pose.linear(), pose.translation());
    }
    fcl::DistanceRequestd request;
    request.enable_nearest_points = points != nullptr;
    fcl::DistanceResultd result;  // shared: every pair prunes against the running minimum
    if (environment)
        for (auto &component : impl_->components)
            for (auto &object : impl_->objects)
                fcl::distance(component.get(), object.get(), request, result);
    if (self)
        for (const auto &[a, b] : model.selfPairs)
            fcl::distance(impl_->components[a].get(), impl_->components[b].get(), request, result);
    if (points)
    {
        points[0] = result.nearest_points[0];
        points[1] = result.nearest_points[1];
    }
    return result.min_distance;
}

double fclMeshDistance(const Mesh &a, const Eigen::Isometry3d &poseA, const Mesh &b, const Eigen::Isometry3d &poseB)
{
    fcl::CollisionObjectd oa(toFcl(a), poseA.linear(), poseA.translation());
    fcl::CollisionObjectd ob(toFcl(b), poseB.linear(), poseB.translation());
    fcl::DistanceRequestd request;
    fcl::DistanceResultd result;
    fcl::distance(&oa, &ob, request, result);
    return result.min_distance;
}
}  // namespace rastercheck::test
