// rastercheck view: the page. Draws the robot and the scene with three.js, puts every coordinate on
// a slider, asks the server (POST api/check) whether the current state collides and shows every
// contact: colliding components in red, the triangles they hit in red on their objects.
// At most one check is in flight: while one runs, moves only remember the latest state, which is
// checked when the answer comes back, so a dragged slider never queues up stale requests.
import * as THREE from '/vendor/three/build/three.module.js';
import {OrbitControls} from '/vendor/three/examples/jsm/controls/OrbitControls.js';

const COLOURS = {
    component: 0x8aa9d6,
    colliding: 0xe01010,
    object: 0xc9c2b4,
    touchedObject: 0xe8a070,
    hit: 0xff1010,
    background: 0xf3f4f6,
};
const $ = (id) => document.getElementById(id);

let model;             // GET api/model
let q;                 // the configuration shown (robot coordinate order)
const undoStack = [];  // configurations before each committed edit
const redoStack = [];
let editStart = null;  // configuration when the current slider drag began
let checkInFlight = false;
let checkWanted = false;
let rasterInFlight = false;
let rasterWanted = null;

// ---- three.js scene --------------------------------------------------------------------------
const renderer = new THREE.WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
renderer.setPixelRatio(window.devicePixelRatio);
$('view').appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(COLOURS.background);
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1e5);
camera.up.set(0, 0, 1);  // robotics frames: z up
const controls = new OrbitControls(camera, renderer.domElement);
controls.screenSpacePanning = true;
const sky = new THREE.HemisphereLight(0xffffff, 0x8d8d8d, 0.75);
sky.position.set(0, 0, 1);  // the sky above, along z
scene.add(sky);
const sun = new THREE.DirectionalLight(0xffffff, 0.55);
sun.position.set(0.4, -0.6, 1.0);
scene.add(sun);

const componentNodes = [];  // per component: a group placed at the link pose, holding its mesh
const objectMeshes = [];
const hitGroup = new THREE.Group();  // red hit triangles and contact points, rebuilt per answer
scene.add(hitGroup);
const clearanceGroup = new THREE.Group();  // a free state's nearest points and the segment between them
scene.add(clearanceGroup);
let sceneRadius = 1;
const sceneCentre = new THREE.Vector3();

function geometryOf(entry)
{
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(entry.vertices), 3));
    geometry.setIndex(new THREE.BufferAttribute(new Uint32Array(entry.triangles), 1));
    geometry.computeVertexNormals();
    geometry.computeBoundingSphere();
    return geometry;
}

function buildScene()
{
    model.components.forEach((component, index) => {
        const material = new THREE.MeshPhongMaterial({color: COLOURS.component, flatShading: true});
        const mesh = new THREE.Mesh(geometryOf(component), material);
        mesh.userData = {label: `link ${component.name}`, kind: 'component', index};
        const node = new THREE.Group();
        node.matrixAutoUpdate = false;
        node.add(mesh);
        scene.add(node);
        componentNodes.push({node, mesh, material});
    });
    const bounds = new THREE.Box3();
    model.objects.forEach((object, index) => {
        const material = new THREE.MeshPhongMaterial({color: COLOURS.object, flatShading: true});
        const mesh = new THREE.Mesh(geometryOf(object), material);
        mesh.userData = {label: `object ${object.name}`, kind: 'object', index};
        scene.add(mesh);
        objectMeshes.push(mesh);
        bounds.expandByObject(mesh);
    });
    if (bounds.isEmpty())
        bounds.set(new THREE.Vector3(-1, -1, -1), new THREE.Vector3(1, 1, 1));
    const sphere = bounds.getBoundingSphere(new THREE.Sphere());
    sceneCentre.copy(sphere.center);
    sceneRadius = Math.max(sphere.radius, 1e-3);
    camera.near = sceneRadius / 1000;
    camera.far = sceneRadius * 100;
    camera.updateProjectionMatrix();
}

// Includes the robot as placed now, so that a robot standing outside the scene stays in view.
function viewBounds()
{
    const bounds = new THREE.Box3();
    objectMeshes.forEach((mesh) => bounds.expandByObject(mesh));
    componentNodes.forEach(({node}) => bounds.expandByObject(node));
    return bounds.isEmpty() ? new THREE.Sphere(sceneCentre, sceneRadius) : bounds.getBoundingSphere(new THREE.Sphere());
}

const VIEW_DIRECTIONS = {
    iso: new THREE.Vector3(1, -1, 0.8),
    front: new THREE.Vector3(0, -1, 0),
    side: new THREE.Vector3(1, 0, 0),
    top: new THREE.Vector3(0, -1e-3, 1),  // not exactly along the up axis, where orbiting is undefined
};

function setView(name)
{
    const sphere = viewBounds();
    const distance = sphere.radius / Math.sin((camera.fov / 2) * Math.PI / 180) * 1.05;
    camera.position.copy(sphere.center).addScaledVector(VIEW_DIRECTIONS[name].clone().normalize(), distance);
    controls.target.copy(sphere.center);
    controls.update();
}

function resize()
{
    const box = $('view').getBoundingClientRect();
    renderer.setSize(Math.max(1, box.width), Math.max(1, box.height));
    camera.aspect = Math.max(1, box.width) / Math.max(1, box.height);
    camera.updateProjectionMatrix();
    requestRender();
}
window.addEventListener('resize', resize);

// Frames are drawn only when something changed (the camera, an answer, playback): a software
// WebGL (no GPU) would otherwise spend a core redrawing the same picture.
let renderWanted = true;
function requestRender()
{
    renderWanted = true;
}
controls.addEventListener('change', requestRender);

function animate()
{
    requestAnimationFrame(animate);
    advancePlayback();
    if (!renderWanted)
        return;
    renderWanted = false;
    renderer.render(scene, camera);
}

// ---- names on hover ----------------------------------------------------------------------------
const raycaster = new THREE.Raycaster();
const pointer = new THREE.Vector2();
renderer.domElement.addEventListener('pointermove', (event) => {
    const box = renderer.domElement.getBoundingClientRect();
    pointer.set(((event.clientX - box.left) / box.width) * 2 - 1, -((event.clientY - box.top) / box.height) * 2 + 1);
    raycaster.setFromCamera(pointer, camera);
    const pickable = componentNodes.map(({mesh}) => mesh).concat(objectMeshes);
    const hit = raycaster.intersectObjects(pickable, false)[0];
    const tooltip = $('tooltip');
    if (!hit)
    {
        tooltip.style.display = 'none';
        return;
    }
    tooltip.textContent = hit.object.userData.label;
    tooltip.style.left = `${event.clientX - box.left + 14}px`;
    tooltip.style.top = `${event.clientY - box.top + 10}px`;
    tooltip.style.display = 'block';
});
renderer.domElement.addEventListener('pointerleave', () => {
    $('tooltip').style.display = 'none';
});

// ---- joints ------------------------------------------------------------------------------------
const jointInputs = [];  // per coordinate: { slider, number }

function formatValue(value)
{
    return Number(value.toFixed(4)).toString();
}

function buildJointControls()
{
    const container = $('joints');
    model.coordinates.forEach((coordinate, i) => {
        const row = document.createElement('div');
        row.className = 'joint';
        const unit = coordinate.unit ? ` (${coordinate.unit})` : '';
        const label = document.createElement('label');
        label.htmlFor = `joint-${i}-number`;
        label.innerHTML = `<span></span><span class="limits"></span>`;
        label.children[0].textContent = coordinate.name + unit;
        label.children[1].textContent = `${formatValue(coordinate.lower)} … ${formatValue(coordinate.upper)}`;
        const inputs = document.createElement('div');
        inputs.className = 'inputs';
        // step "any": the slider holds a typed value exactly instead of snapping it to a grid.
        const coordinateInput = (type, role) =>
        {
            const input = Object.assign(document.createElement('input'), {
                type,
                id: `joint-${i}-${role}`,
                min: coordinate.lower,
                max: coordinate.upper,
                step: 'any',
            });
            input.dataset.coordinate = coordinate.name;
            return input;
        };
        const slider = coordinateInput('range', 'slider');
        const number = coordinateInput('number', 'number');
        // A drag is one edit: the configuration before it is remembered at its first move and
        // committed to the undo stack when the slider is released.
        slider.addEventListener('input', () => {
            if (!editStart)
                editStart = q.slice();
            q[i] = Number(slider.value);
            number.value = formatValue(q[i]);
            stateChanged();
        });
        slider.addEventListener('change', () => commitEdit());
        number.addEventListener('change', () => {
            const value = Number(number.value);
            if (number.value === '' || !Number.isFinite(value))
            {
                number.value = formatValue(q[i]);
                return;
            }
            editStart = q.slice();
            q[i] = Math.min(coordinate.upper, Math.max(coordinate.lower, value));
            commitEdit();
            showConfiguration();
            stateChanged();
        });
        inputs.append(slider, number);
        row.append(label, inputs);
        container.appendChild(row);
        jointInputs.push({slider, number});
    });
}

function showConfiguration()
{
    q.forEach((value, i) => {
        jointInputs[i].slider.value = value;
        if (document.activeElement !== jointInputs[i].number)
            jointInputs[i].number.value = formatValue(value);
    });
}

function sameConfiguration(a, b)
{
    return a.length === b.length && a.every((value, i) => value === b[i]);
}

function commitEdit()
{
    if (editStart && !sameConfiguration(editStart, q))
    {
        undoStack.push(editStart);
        redoStack.length = 0;
    }
    editStart = null;
    updateUndoButtons();
}

/** Sets the whole configuration as one edit (start, goal, playback). */
function jumpTo(configuration)
{
    editStart = q.slice();
    q = configuration.slice();
    commitEdit();
    showConfiguration();
    stateChanged();
}

/** One edit back (undo) or forward (redo): the state shown goes onto the other stack. */
function stepHistory(from, to)
{
    if (!from.length)
        return;
    to.push(q.slice());
    q = from.pop();
    editStart = null;
    updateUndoButtons();
    showConfiguration();
    stateChanged();
}
const undo = () => stepHistory(undoStack, redoStack);
const redo = () => stepHistory(redoStack, undoStack);

function updateUndoButtons()
{
    $('undo').disabled = undoStack.length === 0;
    $('redo').disabled = redoStack.length === 0;
}

window.addEventListener('keydown', (event) => {
    if (!(event.ctrlKey || event.metaKey))
        return;
    const key = event.key.toLowerCase();
    if (key === 'z' && !event.shiftKey)
        undo();
    else if (key === 'y' || (key === 'z' && event.shiftKey))
        redo();
    else
        return;
    event.preventDefault();  // not the number field's own text undo
}, true);

// ---- checking ----------------------------------------------------------------------------------
function stateChanged()
{
    document.body.dataset.busy = 'true';
    requestCheck();
}

// The address bar holds the state once it settles: browsers throttle an address that changes at
// every frame of a drag or a playback.
let addressTimer = null;
function updateAddressSoon()
{
    clearTimeout(addressTimer);
    addressTimer = setTimeout(() => history.replaceState(null, '', `#q=${q.map(formatValue).join(',')}`), 300);
}

async function requestCheck()
{
    if (checkInFlight)
    {
        checkWanted = true;
        return;
    }
    checkInFlight = true;
    checkWanted = false;
    const asked = q.slice();
    const sent = performance.now();
    try
    {
        const response = await fetch('api/check', {
            method: 'POST',
            headers: {'Content-Type': 'application/json'},
            body: JSON.stringify({q: asked}),
        });
        const answer = await response.json();
        if (!response.ok)
            throw new Error(answer.error || `HTTP ${response.status}`);
        showAnswer(asked, answer, performance.now() - sent);
    }
    catch (error)
    {
        const status = $('status');
        status.dataset.state = 'error';
        status.textContent = `Error: ${error.message}`;
    }
    finally
    {
        checkInFlight = false;
        if (checkWanted)
        {
            requestCheck();
        }
        else
        {
            document.body.dataset.busy = 'false';
            updateAddressSoon();
        }
    }
}

function showAnswer(asked, answer, roundTrip)
{
    answer.links.forEach((pose, c) => {
        const node = componentNodes[c].node;
        node.matrix.compose(
            new THREE.Vector3(...pose.position), new THREE.Quaternion(...pose.quaternion), new THREE.Vector3(1, 1, 1));
        node.matrixWorldNeedsUpdate = true;
    });
    const collidingComponents = new Set();
    const touchedObjects = new Set();
    for (const contact of answer.contacts)
    {
        if (contact.kind === 'environment')
        {
            collidingComponents.add(contact.component);
            touchedObjects.add(contact.object);
        }
        else if (contact.kind === 'self')
        {
            collidingComponents.add(contact.component).add(contact.object);
        }
    }
    model.components.forEach((component, c) => {
        componentNodes[c].material.color.setHex(
            collidingComponents.has(component.name) ? COLOURS.colliding : COLOURS.component);
    });
    // A touched object turns see-through, so that the red links inside it show.
    model.objects.forEach((object, o) => {
        const material = objectMeshes[o].material;
        const touched = touchedObjects.has(object.name);
        material.color.setHex(touched ? COLOURS.touchedObject : COLOURS.object);
        material.transparent = touched;
        material.opacity = touched ? 0.45 : 1;
        material.depthWrite = !touched;
    });
    showHits(answer.contacts);
    showClearance(answer.distance);
    requestRender();

    const status = $('status');
    const outOfBounds = answer.contacts.some((contact) => contact.kind === 'out_of_bounds');
    status.dataset.state = answer.valid ? 'valid' : (outOfBounds ? 'out_of_bounds' : 'colliding');
    status.dataset.q = JSON.stringify(asked);
    status.dataset.contacts = String(answer.contacts.length);
    const count = answer.contacts.length;
    if (answer.valid)
        status.textContent = 'Collision-free';
    else if (outOfBounds)
        status.textContent = 'Out of bounds';
    // Conservative mode calls a pair its proofs cannot separate a collision; the exact phase may
    // still find the solids apart.
    else if (!count)
        status.textContent = `Invalid in ${model.mode} mode, no exact contact`;
    else
        status.textContent = `Collision: ${count} contact${count === 1 ? '' : 's'}`;
    $('timing').textContent =
        `check ${answer.milliseconds.toFixed(2)} ms on the server, ${roundTrip.toFixed(0)} ms round trip`;

    const list = $('contacts');
    list.replaceChildren(...answer.contacts.map((contact) => {
        const item = document.createElement('li');
        item.dataset.component = contact.component || '';
        item.dataset.object = contact.object || '';
        if (contact.kind === 'environment' || contact.kind === 'self')
        {
            const pair = document.createElement('div');
            pair.className = 'pair';
            pair.textContent = `${contact.component} ↔ ${contact.object}`;
            const where = document.createElement('div');
            const point = contact.point.map((v) => v.toFixed(3)).join(', ');
            where.textContent = `${contact.triangle >= 0 ? `triangle ${contact.triangle}` : 'contained'} at (${point})`;
            item.append(pair, where);
        }
        else
        {
            item.textContent = contact.description;
        }
        return item;
    }));
    if (!answer.contacts.length)
        list.innerHTML = '<li class="note">none</li>';
    requestRaster(answer.valid ? null : asked);
}

/**
   A free state's clearance: the distance and the pair in the header, and the segment between the
   two nearest points (green, drawn over everything). Nothing for a colliding state.
 */
function showClearance(distance)
{
    for (const child of clearanceGroup.children.slice())
    {
        child.geometry.dispose();
        child.material.dispose();
        clearanceGroup.remove(child);
    }
    const text = $('clearance');
    text.textContent =
        distance ? `clearance ${distance.distance.toFixed(4)} (${distance.component} ↔ ${distance.other})` : '';
    text.dataset.distance = distance ? String(distance.distance) : '';
    if (!distance)
        return;
    const ends = distance.points.map((point) => new THREE.Vector3().fromArray(point));
    const segment = new THREE.Line(new THREE.BufferGeometry().setFromPoints(ends),
                                   new THREE.LineBasicMaterial({color: 0x108030, depthTest: false}));
    segment.renderOrder = 12;
    clearanceGroup.add(segment);
    for (const end of ends)
    {
        const dot = new THREE.Mesh(new THREE.SphereBufferGeometry(sceneRadius * 0.004, 12, 8),
                                   new THREE.MeshBasicMaterial({color: 0x108030, depthTest: false, transparent: true}));
        dot.position.copy(end);
        dot.renderOrder = 12;
        clearanceGroup.add(dot);
    }
}

/**
   Red hit triangles on the surfaces they belong to (pulled towards the camera, so that they win
    over the coplanar face they cover), and a red dot at each contact point, drawn over everything.
    A self-contact's triangle belongs to the other component, in its link frame.
 */
function showHits(contacts)
{
    for (const child of hitGroup.children.slice())
    {
        child.geometry.dispose();
        child.material.dispose();
        hitGroup.remove(child);
    }
    const positions = [];
    const corner = new THREE.Vector3();
    for (const contact of contacts)
    {
        if (contact.triangle === undefined || contact.triangle < 0)
            continue;
        let mesh;
        let matrix = null;
        if (contact.kind === 'environment')
        {
            mesh = model.objects.find((object) => object.name === contact.object);
        }
        else
        {
            const c = model.components.findIndex((component) => component.name === contact.object);
            mesh = model.components[c];
            matrix = componentNodes[c].node.matrix;
        }
        for (let k = 0; k < 3; ++k)
        {
            const v = mesh.triangles[3 * contact.triangle + k];
            corner.fromArray(mesh.vertices, 3 * v);
            if (matrix)
                corner.applyMatrix4(matrix);
            positions.push(corner.x, corner.y, corner.z);
        }
    }
    if (positions.length)
    {
        const geometry = new THREE.BufferGeometry();
        geometry.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
        const faces = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({
            color: COLOURS.hit,
            side: THREE.DoubleSide,
            polygonOffset: true,
            polygonOffsetFactor: -2,
            polygonOffsetUnits: -8,
        }));
        const edges = new THREE.LineSegments(
            new THREE.WireframeGeometry(geometry), new THREE.LineBasicMaterial({color: 0x700000}));
        faces.renderOrder = edges.renderOrder = 10;
        hitGroup.add(faces, edges);
    }
    const dotGeometry = new THREE.SphereBufferGeometry(sceneRadius * 0.006, 12, 8);
    for (const contact of contacts)
    {
        if (!contact.point)
            continue;
        const dot = new THREE.Mesh(dotGeometry, new THREE.MeshBasicMaterial({
            color: COLOURS.hit,
            depthTest: false,
            transparent: true,
        }));
        dot.position.fromArray(contact.point);
        dot.renderOrder = 11;
        hitGroup.add(dot);
    }
}

/** The raster image of the first colliding pair: one image request at a time, as for checks. */
function requestRaster(configuration)
{
    const image = $('raster');
    const note = $('raster-note');
    if (!configuration)
    {
        rasterWanted = null;
        image.hidden = true;
        note.textContent = 'Collision-free: no colliding pair to draw.';
        return;
    }
    if (rasterInFlight)
    {
        rasterWanted = configuration;
        return;
    }
    rasterInFlight = true;
    rasterWanted = null;
    const url = `api/raster?q=${configuration.join(',')}`;
    fetch(url)
        .then(async (response) => {
            if (!response.ok)
            {
                const answer = await response.json();
                image.hidden = true;
                note.textContent = answer.error;
                return;
            }
            const blob = await response.blob();
            if (image.src.startsWith('blob:'))
                URL.revokeObjectURL(image.src);
            image.src = URL.createObjectURL(blob);
            image.hidden = false;
            note.textContent =
                'Pixels of the first colliding pair: blue the link, sand the object, red where the ray finds them overlapping.';
        })
        .catch((error) => {
            note.textContent = `raster image: ${error.message}`;
        })
        .finally(() => {
            rasterInFlight = false;
            if (rasterWanted)
                requestRaster(rasterWanted);
        });
}

// ---- path playback -----------------------------------------------------------------------------
let playing = false;
let lastFrame = 0;

function pathState(t)
{
    const rows = model.path;
    const r = Math.min(Math.floor(t), rows.length - 2);
    const f = t - r;
    return rows[r].map((value, i) => (1 - f) * value + f * rows[r + 1][i]);
}

function setTimeline(t)
{
    $('timeline').value = t;
    q = model.path.length > 1 ? pathState(t) : model.path[0].slice();
    showConfiguration();
    stateChanged();
}

function advancePlayback()
{
    const now = performance.now();
    const elapsed = (now - lastFrame) / 1000;
    lastFrame = now;
    if (!playing)
        return;
    const segments = model.path.length - 1;
    const secondsPerSegment = Math.min(2, 20 / segments);
    let t = Number($('timeline').value) + elapsed / secondsPerSegment;
    if (t >= segments)
    {
        t = segments;
        togglePlay(false);
    }
    setTimeline(t);
}

function togglePlay(play = !playing)
{
    if (play && !playing)
    {
        if (Number($('timeline').value) >= model.path.length - 1)
            $('timeline').value = 0;
        editStart = q.slice();  // playback is one edit: undo returns to where it started
    }
    if (!play && playing)
        commitEdit();
    playing = play;
    $('play').textContent = playing ? 'Pause' : 'Play';
}

function setupPlayback()
{
    const timeline = $('timeline');
    $('play').addEventListener('click', () => togglePlay());
    timeline.addEventListener('input', () => {
        togglePlay(false);
        if (!editStart)
            editStart = q.slice();
        setTimeline(Number(timeline.value));
    });
    timeline.addEventListener('change', () => commitEdit());
}

/** Shows model.path on the timeline: its own states checked in one batch, red marks where they collide. */
async function showPath()
{
    if (!model.path.length)
        return;
    togglePlay(false);
    const timeline = $('timeline');
    timeline.max = Math.max(0, model.path.length - 1);
    timeline.value = 0;
    $('playback').hidden = false;
    $('play').disabled = model.path.length < 2;
    const response = await fetch('api/check', {
        method: 'POST',
        headers: {'Content-Type': 'application/json'},
        body: JSON.stringify({states: model.path}),
    });
    const answer = await response.json();
    if (!response.ok)
    {
        $('path-info').textContent = answer.error;
        return;
    }
    const colliding = answer.valid.filter((valid) => !valid).length;
    $('path-info').textContent = `${model.path.length} path states, ${colliding} colliding`;
    $('path-info').dataset.colliding = String(colliding);
    const canvas = $('path-verdicts');
    canvas.width = canvas.clientWidth || 600;
    const context = canvas.getContext('2d');
    context.clearRect(0, 0, canvas.width, canvas.height);
    const segments = Math.max(1, model.path.length - 1);
    answer.valid.forEach((valid, r) => {
        context.fillStyle = valid ? '#1a8a3a' : '#e01010';
        const x = (r / segments) * canvas.width;
        context.fillRect(Math.min(x, canvas.width - 3), 0, 3, canvas.height);
    });
}

// ---- planning ----------------------------------------------------------------------------------
let goal = null;  // what Plan aims at: the problem's goal, or one set with "Set goal"

function showGoal(text)
{
    $('plan').disabled = !goal;
    $('plan-info').textContent = text || (goal ? '' : 'No goal: set one with "Set goal".');
}

/** POST api/plan from the current configuration to the goal; the path found replaces the timeline's
    and plays. */
async function plan()
{
    $('plan').disabled = true;
    $('plan-info').dataset.state = 'planning';
    $('plan-info').textContent = 'planning…';
    const response = await fetch('api/plan', {
        method: 'POST',
        headers: {'Content-Type': 'application/json'},
        body: JSON.stringify({start: q, goal, planner: $('planner').value, time_limit: Number($('time-limit').value)}),
    });
    const answer = await response.json();
    $('plan').disabled = false;
    if (!response.ok || !answer.solved)
    {
        $('plan-info').dataset.state = 'failed';
        $('plan-info').textContent = response.ok ? `${answer.planner}: ${answer.message}` : answer.error;
        return;
    }
    model.path = answer.path;
    await showPath();
    $('plan-info').textContent =
        `${answer.planner}: ${answer.path.length} states in ${answer.seconds.toFixed(2)} s`;
    $('plan-info').dataset.state = 'solved';  // after the timeline shows the path
    togglePlay(true);
}

function setupPlanning()
{
    goal = model.goal ? model.goal.slice() : null;
    showGoal();
    $('plan').addEventListener('click', plan);
    $('set-goal').addEventListener('click', () => {
        goal = q.slice();
        showGoal('Goal set to the current configuration.');
    });
}

// ---- start -------------------------------------------------------------------------------------
function initialConfiguration()
{
    const fromAddress = /q=([^&]*)/.exec(location.hash);
    if (fromAddress)
    {
        const values = fromAddress[1].split(',').map(Number);
        if (values.length === model.coordinates.length && values.every(Number.isFinite))
            return values;
    }
    return (model.start || model.neutral).slice();
}

async function main()
{
    const response = await fetch('api/model');
    model = await response.json();
    document.title = `rastercheck view: ${model.title}`;
    $('title').textContent = model.title;
    const triangles = (list) => list.reduce((sum, entry) => sum + entry.triangles.length / 3, 0);
    const robotTriangles = triangles(model.components), sceneTriangles = triangles(model.objects);
    $('model-info').textContent = `${model.robot}: ${model.components.length} links with geometry ` +
        `(${robotTriangles} triangles), ${model.objects.length} scene objects (${sceneTriangles} triangles); ` +
        `${model.mode} mode, padding ${model.padding}, ${model.backend} backend.`;
    buildScene();
    buildJointControls();
    q = initialConfiguration();
    for (const [id, configuration] of [['to-start', model.start], ['to-goal', model.goal]])
    {
        if (!configuration)
            continue;
        $(id).hidden = false;
        $(id).addEventListener('click', () => jumpTo(configuration));
    }
    $('undo').addEventListener('click', undo);
    $('redo').addEventListener('click', redo);
    document.querySelectorAll('[data-view]').forEach((button) => {
        button.addEventListener('click', () => setView(button.dataset.view));
    });
    showConfiguration();
    resize();
    stateChanged();
    setupPlayback();
    showPath();
    setupPlanning();
    animate();
    // The first answer places the robot: frame the view on it and the scene then.
    const framed = setInterval(() => {
        if (document.body.dataset.busy === 'false')
        {
            clearInterval(framed);
            setView('iso');
        }
    }, 50);
}

main().catch((error) => {
    $('status').dataset.state = 'error';
    $('status').textContent = `Error: ${error.message}`;
});
