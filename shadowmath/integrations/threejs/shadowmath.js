// shadowmath for three.js: give a three.js light the shadow camera of a shadowmath fit.
//
// The data comes from shadowmath.integrations.threejs (Python): shadow_data (a directional
// or spot light), point_shadow_data (a point light) and cascade_shadow_data (one camera per
// cascade). This module imports nothing: it works with whatever three.js instance the
// page uses (r187 tested).
//
//   import { applyShadow } from './shadowmath.js';
//   applyShadow(sun, data);          // once, and again with each new fit
//
// The light itself is never written: position, target, angle, distance, intensity stay
// what the application set. Only light.shadow changes: its mapSize, bias, camera fields
// (for helpers), and, on that one shadow object, updateMatrices, which three.js calls
// before drawing each frame: three.js's own puts the camera at the light looking at the
// target and, for a spot light, rebuilds the field of view from the cone
// (SpotLightShadow.updateMatrices); the replacement places the camera at the fit's pose
// and sets the fit's window with three.js's makeOrthographic / makePerspective in the
// camera's coordinate system (WebGL depth -1..1, WebGPU 0..1), then builds shadow.matrix
// as three.js does (LightShadow._updateMatrix). For a point light, three.js places the six
// cube faces itself; only near and far are set, and far is kept against three.js's reset
// to light.distance each frame (WebGLShadowMap.js).

const KEY = '__shadowmath';
const FIELDS = ['near', 'far', 'left', 'right', 'top', 'bottom', 'fov', 'aspect'];

function saved(light) {
	// What applyShadow changes, as the application left it: removeShadow restores it.
	const shadow = light.shadow;
	const camera = {};
	for (const f of FIELDS) if (f in shadow.camera) camera[f] = shadow.camera[f];
	return { camera, mapSize: shadow.mapSize.toArray(), bias: shadow.bias };
}

function setMapSize(shadow, size) {
	if (shadow.mapSize.x === size[0] && shadow.mapSize.y === size[1]) return;
	shadow.mapSize.set(size[0], size[1]);
	if (shadow.map) { // three.js allocates a new map of the new size on the next frame
		shadow.map.dispose();
		shadow.map = null;
	}
}

function setProjection(camera, data) {
	const args = [data.left, data.right, data.top, data.bottom, data.near, data.far,
		camera.coordinateSystem, camera.reversedDepth];
	if (data.type === 'orthographic') camera.projectionMatrix.makeOrthographic(...args);
	else camera.projectionMatrix.makePerspective(...args);
	camera.projectionMatrixInverse.copy(camera.projectionMatrix).invert();
}

function placeCamera(camera, data) {
	camera.matrix.fromArray(data.matrixWorld);
	camera.matrix.decompose(camera.position, camera.quaternion, camera.scale);
	camera.up.fromArray(data.up);
	camera.updateMatrixWorld(true);
}

function fittedUpdateMatrices() {
	// Installed as light.shadow.updateMatrices: `this` is the shadow.
	const data = this[KEY].data;
	const camera = this.camera;
	placeCamera(camera, data);
	setProjection(camera, data);
	this._updateMatrix(camera, this.matrix, this._frustum);
}

function setCameraFields(camera, data) {
	// For CameraHelper and anyone reading the camera; the projection is set separately.
	camera.near = data.near;
	camera.far = data.far;
	if (data.type === 'orthographic') {
		Object.assign(camera, { left: data.left, right: data.right, top: data.top, bottom: data.bottom });
	} else {
		camera.fov = data.fov;
		camera.aspect = data.aspect;
	}
}

function applyFrustum(light, data) {
	const shadow = light.shadow;
	const wanted = data.type === 'orthographic' ? 'isOrthographicCamera' : 'isPerspectiveCamera';
	if (!shadow.camera[wanted]) {
		throw new Error(`shadowmath: a ${data.type} fit for a light whose shadow camera is not ${data.type}`);
	}
	if (!shadow[KEY]) {
		const own = Object.prototype.hasOwnProperty.call(shadow, 'updateMatrices');
		shadow[KEY] = { saved: saved(light), updateMatrices: own ? shadow.updateMatrices : null };
		shadow.updateMatrices = fittedUpdateMatrices;
	}
	shadow[KEY].data = data;
	setCameraFields(shadow.camera, data);
	placeCamera(shadow.camera, data);
	setProjection(shadow.camera, data);
}

function applyCube(light, data) {
	const shadow = light.shadow;
	const camera = shadow.camera;
	if (!light.isPointLight) throw new Error('shadowmath: cube data is for a PointLight');
	if (!shadow[KEY]) {
		shadow[KEY] = { saved: saved(light) };
		// three.js sets camera.far = light.distance || camera.far before each frame: keep ours.
		Object.defineProperty(camera, 'far', {
			configurable: true,
			get() { return shadow[KEY].data.far; },
			set(value) { /* the fitted far stays */ },
		});
	}
	shadow[KEY].data = data;
	camera.near = data.near;
	camera.updateProjectionMatrix();
}

/**
 * Apply shadowmath's data to a three.js light's shadow (and keep it applied every frame).
 * @param {Light} light a DirectionalLight or SpotLight (data of shadow_data) or a
 *   PointLight (data of point_shadow_data).
 * @param {object} data the JSON of the Python side.
 */
export function applyShadow(light, data) {
	if (!light || !light.shadow) throw new Error('shadowmath: light has no shadow');
	if (data.type === 'cube') applyCube(light, data);
	else applyFrustum(light, data);
	setMapSize(light.shadow, data.mapSize);
	light.shadow.bias = data.bias;
	light.shadow.needsUpdate = true;
}

/**
 * Apply cascade_shadow_data: cascade i to lights[i] (directional lights sharing one direction).
 */
export function applyCascades(lights, data) {
	if (lights.length !== data.cascades.length) {
		throw new Error(`shadowmath: ${data.cascades.length} cascades for ${lights.length} lights`);
	}
	data.cascades.forEach((cascade, i) => applyShadow(lights[i], cascade));
}

/**
 * Give a light back to three.js's own shadow camera: its updateMatrices, and the camera
 * fields, mapSize and bias the application had set before the first applyShadow.
 */
export function removeShadow(light) {
	const shadow = light.shadow;
	const state = shadow && shadow[KEY];
	if (!state) return;
	if ('updateMatrices' in state) {
		if (state.updateMatrices) shadow.updateMatrices = state.updateMatrices;
		else delete shadow.updateMatrices;
	} else {
		delete shadow.camera.far; // the getter of applyCube
	}
	Object.assign(shadow.camera, state.saved.camera);
	setMapSize(shadow, state.saved.mapSize);
	shadow.bias = state.saved.bias;
	delete shadow[KEY];
	shadow.camera.updateProjectionMatrix();
	shadow.needsUpdate = true;
}
