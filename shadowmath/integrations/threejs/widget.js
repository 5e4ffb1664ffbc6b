// The ShadowWidget's view (anywidget). three.js and shadowmath.js arrive as strings in the
// widget's state (three_source, module_source) and are imported from Blob URLs: nothing is
// loaded from the network, and a notebook saved with its widget state draws offline.

const cache = {};
async function importSource(source) {
	if (!cache[source.length]) {
		const url = URL.createObjectURL(new Blob([source], { type: 'text/javascript' }));
		cache[source.length] = import(url);
	}
	return cache[source.length];
}

function buildLight(THREE, spec) {
	let light;
	if (spec.kind === 'directional') light = new THREE.DirectionalLight(0xffffff, 3);
	else if (spec.kind === 'spot') light = new THREE.SpotLight(0xffffff, 30, 0, spec.angle, 0.05, 0);
	else light = new THREE.PointLight(0xffffff, 30, 0, 0);
	light.position.fromArray(spec.position);
	if (light.target) light.target.position.fromArray(spec.target || [0, 0, 0]);
	light.castShadow = true;
	light.userData.intensity = light.intensity; // shared among a sun's cascades
	light.shadow.normalBias = 0.02; // the floor casts and receives: no acne on it
	return light;
}

function buildMeshes(THREE, meshes) {
	return meshes.map((m) => {
		const geometry = new THREE.BufferGeometry();
		geometry.setAttribute('position', new THREE.Float32BufferAttribute(m.positions, 3));
		geometry.setIndex(m.indices);
		geometry.computeVertexNormals();
		const mesh = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({ color: m.color, side: THREE.DoubleSide }));
		mesh.castShadow = true;
		mesh.receiveShadow = true;
		return mesh;
	});
}

async function render({ model, el }) {
	const THREE = await importSource(model.get('three_source'));
	const sm = await importSource(model.get('module_source'));
	const width = el.clientWidth || 640;
	const height = model.get('height');
	const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
	renderer.setSize(width, height);
	renderer.shadowMap.enabled = true;
	el.appendChild(renderer.domElement);
	const status = document.createElement('div');
	status.style.font = '12px sans-serif';
	el.appendChild(status);

	const scene = new THREE.Scene();
	scene.background = new THREE.Color(0xf4f4f4);
	scene.add(new THREE.AmbientLight(0xffffff, 0.35));
	const view = model.get('camera');
	const camera = new THREE.PerspectiveCamera(view.fov ?? 45, width / height, view.near ?? 0.05, view.far ?? 500);
	camera.up.set(0, 0, 1);
	camera.position.fromArray(view.position);
	const orbit = new THREE.OrbitControls(camera, renderer.domElement);
	orbit.target.fromArray(view.target);
	orbit.update();
	function sendCamera() { // the viewer's camera, back to Python (cascades are refitted to it)
		const { fov, aspect, near, far } = camera;
		model.set('camera', { position: camera.position.toArray(), target: orbit.target.toArray(), fov, aspect, near, far });
		model.save_changes();
	}
	orbit.addEventListener('end', sendCamera);
	if (view.aspect !== camera.aspect) sendCamera();

	let meshes = [];
	let light = null; // the dragged light; with cascades, cascade 0's
	let extra = []; // cascades 1..N-1: lights like `light`
	let helpers = [];
	let frozen = false; // set by the test hook `readback`
	const lights = () => [light, ...extra];
	let gizmo = null;
	const mapView = new THREE.Mesh(new THREE.PlaneGeometry(1, 1), new THREE.MeshBasicMaterial());
	const hud = new THREE.Scene();
	hud.add(mapView);
	const hudCamera = new THREE.OrthographicCamera(0, 1, 1, 0, -1, 1);

	function rebuildMeshes() {
		meshes.forEach((m) => scene.remove(m));
		meshes = buildMeshes(THREE, model.get('meshes'));
		meshes.forEach((m) => scene.add(m));
	}

	function setLightCount(n) {
		while (extra.length > n - 1) {
			const l = extra.pop();
			sm.removeShadow(l);
			scene.remove(l, l.target);
			l.dispose();
		}
		while (extra.length < n - 1) {
			const l = buildLight(THREE, model.get('light'));
			l.position.copy(light.position);
			scene.add(l, l.target);
			extra.push(l);
		}
	}

	function rebuildLight() {
		setLightCount(1);
		if (light) { scene.remove(light); if (light.target) scene.remove(light.target); light.dispose(); }
		if (gizmo) { scene.remove(gizmo.getHelper()); gizmo.dispose(); }
		light = buildLight(THREE, model.get('light'));
		scene.add(light);
		if (light.target) scene.add(light.target);
		gizmo = new THREE.TransformControls(camera, renderer.domElement);
		gizmo.attach(light);
		gizmo.addEventListener('dragging-changed', (e) => {
			orbit.enabled = !e.value;
			if (!e.value) {
				model.set('light', { ...model.get('light'), position: light.position.toArray() });
				model.save_changes();
			}
		});
		scene.add(gizmo.getHelper());
		applyFit();
	}

	function applyFit() {
		const data = model.get('shadow');
		const fitted = model.get('fitted') && data && data.type;
		const cascades = fitted && data.type === 'cascades' && light.isDirectionalLight;
		const n = cascades ? data.cascades.length : 1;
		setLightCount(n);
		lights().forEach((l) => { sm.removeShadow(l); l.intensity = l.userData.intensity / n; });
		if (cascades) sm.applyCascades(lights(), data);
		else if (fitted && data.type !== 'cascades') sm.applyShadow(light, data);
		helpers.forEach((h) => { scene.remove(h); h.dispose(); });
		helpers = [];
		if (model.get('show_frustum') && !light.isPointLight) {
			helpers = lights().map((l) => new THREE.CameraHelper(l.shadow.camera));
			helpers.forEach((h) => scene.add(h));
		}
		status.textContent = model.get('fit_error') || (model.get('fitted') ? 'fitted shadow camera' : "three.js's default shadow camera");
	}

	function frame() {
		if (frozen || (!el.isConnected && renderer.domElement.parentNode !== el)) return;
		orbit.update();
		extra.forEach((l) => l.position.copy(light.position));
		helpers.forEach((h) => h.update());
		renderer.autoClear = true;
		renderer.render(scene, camera);
		const map = light && light.shadow.map;
		if (model.get('show_map') && map && !light.isPointLight) {
			mapView.material.map = map.texture;
			mapView.material.needsUpdate = true;
			const s = Math.min(width, height) / 3;
			renderer.autoClear = false;
			renderer.setViewport(width - s - 8, 8, s, s);
			mapView.position.set(0.5, 0.5, 0);
			renderer.render(hud, hudCamera);
			renderer.setViewport(0, 0, width, height);
		}
		requestAnimationFrame(frame);
	}

	rebuildMeshes();
	rebuildLight();
	model.on('change:meshes', rebuildMeshes);
	model.on('change:shadow', applyFit);
	model.on('change:fitted', applyFit);
	model.on('change:show_frustum', applyFit);
	model.on('change:light', () => {
		const spec = model.get('light');
		if (spec.kind !== (light.isDirectionalLight ? 'directional' : light.isSpotLight ? 'spot' : 'point')) rebuildLight();
		else lights().forEach((l) => l.position.fromArray(spec.position));
	});

	// Test hook (the browser tests read the widget's pixels): stop the interactive loop and
	// draw once on a `size` [w, h] canvas through an orthographic camera looking down -z
	// onto `view` [left, right, bottom, top]; meshes whose index is not in `receivers` are
	// drawn into the shadow maps only; no helpers, gizmo or map picture; with `solo` i, only
	// cascade i lights the scene (at the sun's intensity). Returns the red channel, bottom
	// row first.
	function readback({ size, view: v, receivers, solo }) {
		frozen = true;
		const [w, h] = size;
		renderer.setSize(w, h);
		const top = new THREE.OrthographicCamera(v[0], v[1], v[3], v[2], 0.1, 100);
		top.position.set(0, 0, 50);
		top.lookAt(0, 0, 0);
		meshes.forEach((m, i) => { if (!receivers.includes(i)) m.layers.set(1); });
		[gizmo.getHelper(), ...helpers].forEach((o) => { o.visible = false; });
		lights().forEach((l, i) => {
			l.shadow.camera.layers.enable(1);
			if (solo !== undefined) l.intensity = i === solo ? l.userData.intensity : 0;
		});
		renderer.render(scene, top);
		renderer.render(scene, top);
		const gl = renderer.getContext();
		const pixels = new Uint8Array(w * h * 4);
		gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
		return Array.from({ length: w * h }, (_, i) => pixels[4 * i]);
	}
	window.__shadowmathWidget = { renderer, scene, camera, readback, get light() { return light; }, get lights() { return lights(); } };
	requestAnimationFrame(frame);
	return () => { renderer.dispose(); };
}

export default { render };
